#include "ov_msckf_ton/init/dynamic_init.h"
#include "ov_core/math/so3.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace ovton::msckf {

using ovton::core::ImuData;
using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

namespace {

constexpr int kNg = 11; ///< global unknowns: v0 (3), gravity direction (2), b_g (3), b_a (3)
using VecG = Eigen::Matrix<double, kNg, 1>;
using MatG = Eigen::Matrix<double, kNg, kNg>;
using MatG3 = Eigen::Matrix<double, kNg, 3>;

ImuData lerp(const ImuData &a, const ImuData &b, int64_t t) {
  const double u = static_cast<double>(t - a.t_imu_ns) / static_cast<double>(b.t_imu_ns - a.t_imu_ns);
  ImuData o;
  o.t_imu_ns = t;
  o.wm = a.wm + u * (b.wm - a.wm);
  o.am = a.am + u * (b.am - a.am);
  return o;
}

/// Two vectors spanning the plane orthogonal to the unit vector u.
Eigen::Matrix<double, 3, 2> tangent_basis(const Vec3 &u) {
  const Vec3 a = std::abs(u.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 b1 = (a - u * u.dot(a)).normalized();
  Eigen::Matrix<double, 3, 2> B;
  B.col(0) = b1;
  B.col(1) = u.cross(b1);
  return B;
}

/// World (z up, gravity along −z) in I0 coordinates: yaw follows I0's x axis, as the static initialiser does.
Mat3 world_from_i0(const Vec3 &u_gravity) {
  const Vec3 z = -u_gravity;
  Vec3 x = Vec3::UnitX() - z * z.x();
  if (x.norm() < 0.1)
    x = Vec3::UnitY() - z * z.y();
  x.normalize();
  Mat3 R_I0W;
  R_I0W << x, z.cross(x), z;
  return R_I0W.transpose();
}

struct Obs {
  int frame;
  int feat;
  Vec2 z; ///< normalised coordinates
};

struct Params {
  Vec3 v0 = Vec3::Zero();
  Vec3 u = -Vec3::UnitZ(); ///< gravity direction in I0
  Vec3 bg = Vec3::Zero(), ba = Vec3::Zero();
  std::vector<Vec3> pf;
};

/// The window's problem: frames, observations, extrinsics, and the pre-integration it re-runs when biases change.
struct Problem {
  const std::deque<ImuData> &imu;
  std::vector<int64_t> t_ns;
  std::vector<double> t; ///< seconds since the first frame
  std::vector<Obs> obs;
  int n_feat = 0;
  Mat3 R_CB;
  Vec3 p_CB;
  double G = 9.81;
  double scale = 1.0; ///< normalised units -> whitened (focal / sigma_px)

  bool integrate(const Vec3 &bg, const Vec3 &ba, std::vector<Preintegrated> &pre) const {
    return preintegrate(imu, t_ns.front(), t_ns, bg, ba, pre);
  }
  Vec3 position(const Params &x, const std::vector<Preintegrated> &pre, int k) const {
    return x.v0 * t[k] + 0.5 * G * x.u * t[k] * t[k] + pre[k].p;
  }
  /// Point of observation i in its camera.
  Vec3 point_in_camera(const Params &x, const std::vector<Preintegrated> &pre, const Obs &o) const {
    return R_CB * (pre[o.frame].R.transpose() * (x.pf[o.feat] - position(x, pre, o.frame))) + p_CB;
  }
  /// Whitened residuals (2 per observation); a point behind the camera gets a large constant residual.
  void residuals(const Params &x, const std::vector<Preintegrated> &pre, Eigen::VectorXd &r) const {
    r.resize(2 * obs.size());
    for (size_t i = 0; i < obs.size(); ++i) {
      const Vec3 pc = point_in_camera(x, pre, obs[i]);
      r.segment<2>(2 * i) = pc.z() > 1e-3 ? Vec2(scale * (pc.head<2>() / pc.z() - obs[i].z)) : Vec2(1e3, 1e3);
    }
  }
};

double huber_weight(double s, double k) {
  return s <= k ? 1.0 : k / s;
}

double huber_cost(double s, double k) {
  return s <= k ? 0.5 * s * s : k * (s - 0.5 * k);
}

double total_cost(const Problem &pb, const Eigen::VectorXd &r, const Params &x, double k, double sbg, double sba) {
  double c = 0.0;
  for (size_t i = 0; i < pb.obs.size(); ++i)
    c += huber_cost(r.segment<2>(2 * i).norm(), k);
  return c + 0.5 * (x.bg / sbg).squaredNorm() + 0.5 * (x.ba / sba).squaredNorm();
}

/// Minimises gᵀA g − 2cᵀg subject to |g| = G: g = (A − λI)⁻¹ c with λ below A's smallest eigenvalue, found by
/// bisection on the (monotonic) norm.
Vec3 solve_on_sphere(const Mat3 &A, const Vec3 &c, double G) {
  Eigen::SelfAdjointEigenSolver<Mat3> es(A);
  const Vec3 lam = es.eigenvalues(), d = es.eigenvectors().transpose() * c;
  const auto g_of = [&](double t) { // λ = λ_min − t, t > 0
    Vec3 y;
    for (int i = 0; i < 3; ++i)
      y(i) = d(i) / (lam(i) - lam(0) + t);
    return Vec3(es.eigenvectors() * y);
  };
  double hi = std::max(d.norm() / G, 1e-12), lo = hi * 1e-12;
  for (int it = 0; it < 200; ++it) {
    const double mid = std::sqrt(lo * hi);
    (g_of(mid).norm() > G ? lo : hi) = mid;
  }
  const Vec3 g = g_of(hi);
  return g.norm() > 1e-9 ? Vec3(g.normalized() * G) : Vec3(0, 0, -G);
}

/// Closed-form start with zero biases: bearing × point = 0 is linear in (p_f, v0, g0). Features are eliminated per
/// feature (Schur complement), v0 next, and g0 solved on the sphere |g0| = G. Returns false when degenerate.
bool linear_start(const Problem &pb, const std::vector<Preintegrated> &pre, Params &x) {
  using Mat36 = Eigen::Matrix<double, 3, 6>;
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  std::vector<Mat3> Hff(pb.n_feat, Mat3::Zero());
  std::vector<Mat36> Hfy(pb.n_feat, Mat36::Zero());
  std::vector<Vec3> bf(pb.n_feat, Vec3::Zero());
  Mat6 Hyy = Mat6::Zero();
  Vec6 by = Vec6::Zero();
  for (const Obs &o : pb.obs) {
    const double t = pb.t[o.frame];
    const Mat3 A = pb.R_CB * pre[o.frame].R.transpose();
    for (int row = 0; row < 2; ++row) {
      Vec3 c = Vec3::Zero();
      c(row) = 1.0;
      c(2) = -o.z(row);
      const Eigen::RowVector3d a = c.transpose() * A;
      Eigen::Matrix<double, 1, 6> ay;
      ay << -t * a, -0.5 * t * t * a;
      const double rhs = a.dot(pre[o.frame].p) - c.dot(pb.p_CB);
      Hff[o.feat] += a.transpose() * a;
      Hfy[o.feat] += a.transpose() * ay;
      bf[o.feat] += a.transpose() * rhs;
      Hyy += ay.transpose() * ay;
      by += ay.transpose() * rhs;
    }
  }
  std::vector<Mat3> Hff_inv(pb.n_feat);
  for (int f = 0; f < pb.n_feat; ++f) {
    Hff_inv[f] = (Hff[f] + 1e-9 * Hff[f].trace() * Mat3::Identity()).inverse();
    Hyy -= Hfy[f].transpose() * Hff_inv[f] * Hfy[f];
    by -= Hfy[f].transpose() * Hff_inv[f] * bf[f];
  }
  const Mat3 Hvv = Hyy.topLeftCorner<3, 3>(), Hvg = Hyy.topRightCorner<3, 3>(), Hgg = Hyy.bottomRightCorner<3, 3>();
  Eigen::LDLT<Mat3> vv(Hvv);
  if (vv.info() != Eigen::Success)
    return false;
  const Mat3 A = Hgg - Hvg.transpose() * vv.solve(Hvg);
  const Vec3 c = by.tail<3>() - Hvg.transpose() * vv.solve(Vec3(by.head<3>()));
  const Vec3 g0 = solve_on_sphere(A, c, pb.G);
  x.u = g0 / pb.G;
  x.v0 = vv.solve(Vec3(by.head<3>() - Hvg * g0));
  Vec6 y;
  y << x.v0, g0;
  x.pf.resize(pb.n_feat);
  for (int f = 0; f < pb.n_feat; ++f)
    x.pf[f] = Hff_inv[f] * (bf[f] - Hfy[f] * y);
  return x.v0.allFinite() && x.u.allFinite();
}

/// Normal equations of the whitened, Huber-weighted problem in its bundle-adjustment structure: globals, per-feature
/// blocks and their coupling. Bias columns by central differences (each re-runs the pre-integration).
struct Normal {
  MatG Hgg = MatG::Zero();
  VecG bg = VecG::Zero();
  std::vector<Mat3> Hff;
  std::vector<MatG3> Hgf;
  std::vector<Vec3> bf;
};

bool build_normal(const Problem &pb, const Params &x, const std::vector<Preintegrated> &pre, const Eigen::VectorXd &r,
                  double k, double sbg, double sba, Normal &ne) {
  const size_t m = pb.obs.size();
  Eigen::Matrix<double, Eigen::Dynamic, 6> Jb(2 * m, 6);
  for (int i = 0; i < 6; ++i) {
    const double h = i < 3 ? 1e-5 : 1e-4;
    Eigen::VectorXd rp, rm;
    for (int sgn : {1, -1}) {
      Params xp = x;
      (i < 3 ? xp.bg(i) : xp.ba(i - 3)) += sgn * h;
      std::vector<Preintegrated> pp;
      if (!pb.integrate(xp.bg, xp.ba, pp))
        return false;
      pb.residuals(xp, pp, sgn > 0 ? rp : rm);
    }
    Jb.col(i) = (rp - rm) / (2 * h);
  }
  const Eigen::Matrix<double, 3, 2> B = tangent_basis(x.u);
  const Eigen::Matrix<double, 3, 2> dg_dd = -pb.G * ovton::core::skew(x.u) * B;
  ne = Normal();
  ne.Hff.assign(pb.n_feat, Mat3::Zero());
  ne.Hgf.assign(pb.n_feat, MatG3::Zero());
  ne.bf.assign(pb.n_feat, Vec3::Zero());
  for (size_t i = 0; i < m; ++i) {
    const Obs &o = pb.obs[i];
    const Vec3 pc = pb.point_in_camera(x, pre, o);
    if (!(pc.z() > 1e-3))
      continue;
    const double iz = 1.0 / pc.z();
    Eigen::Matrix<double, 2, 3> Jp;
    Jp << iz, 0, -pc.x() * iz * iz, 0, iz, -pc.y() * iz * iz;
    const Eigen::Matrix<double, 2, 3> Jf = pb.scale * Jp * pb.R_CB * pre[o.frame].R.transpose();
    const double t = pb.t[o.frame];
    Eigen::Matrix<double, 2, kNg> Jg;
    Jg << -t * Jf, -0.5 * t * t * Jf * dg_dd, Jb.middleRows<2>(2 * i);
    const Vec2 ri = r.segment<2>(2 * i);
    const double w = huber_weight(ri.norm(), k);
    ne.Hgg += w * Jg.transpose() * Jg;
    ne.bg -= w * Jg.transpose() * ri;
    ne.Hff[o.feat] += w * Jf.transpose() * Jf;
    ne.Hgf[o.feat] += w * Jg.transpose() * Jf;
    ne.bf[o.feat] -= w * Jf.transpose() * ri;
  }
  ne.Hgg.block<3, 3>(5, 5) += Mat3::Identity() / (sbg * sbg);
  ne.Hgg.block<3, 3>(8, 8) += Mat3::Identity() / (sba * sba);
  ne.bg.segment<3>(5) -= x.bg / (sbg * sbg);
  ne.bg.segment<3>(8) -= x.ba / (sba * sba);
  return true;
}

/// Schur complement on the features: the reduced system of the globals (marginal information when lambda = 0).
MatG reduced(const Normal &ne, double lambda, VecG *rhs, std::vector<Mat3> *Hff_inv) {
  MatG S = ne.Hgg;
  S.diagonal() *= 1.0 + lambda;
  if (rhs)
    *rhs = ne.bg;
  if (Hff_inv)
    Hff_inv->resize(ne.Hff.size());
  for (size_t f = 0; f < ne.Hff.size(); ++f) {
    Mat3 H = ne.Hff[f];
    H.diagonal() *= 1.0 + lambda;
    H.diagonal().array() += 1e-12;
    const Mat3 Hi = H.inverse();
    S -= ne.Hgf[f] * Hi * ne.Hgf[f].transpose();
    if (rhs)
      *rhs -= ne.Hgf[f] * Hi * ne.bf[f];
    if (Hff_inv)
      (*Hff_inv)[f] = Hi;
  }
  return S;
}

Params apply_step(const Params &x, const VecG &dg, const std::vector<Vec3> &df) {
  Params y = x;
  y.v0 += dg.head<3>();
  y.u = (ovton::core::so3_exp(tangent_basis(x.u) * dg.segment<2>(3)) * x.u).normalized();
  y.bg += dg.segment<3>(5);
  y.ba += dg.segment<3>(8);
  for (size_t f = 0; f < y.pf.size(); ++f)
    y.pf[f] += df[f];
  return y;
}

struct StateAtK {
  Mat3 R;
  Vec3 p, v, bg, ba;
};

StateAtK state_at_newest(const Problem &pb, const Params &x, const std::vector<Preintegrated> &pre) {
  const int K = static_cast<int>(pb.t.size()) - 1;
  const Mat3 R_WI0 = world_from_i0(x.u);
  StateAtK s;
  s.R = R_WI0 * pre[K].R;
  s.p = R_WI0 * pb.position(x, pre, K);
  s.v = R_WI0 * (x.v0 + pb.G * x.u * pb.t[K] + pre[K].v);
  s.bg = x.bg;
  s.ba = x.ba;
  return s;
}

/// d(state error at the newest frame) / d(globals), by central differences (the world frame moves with gravity).
bool state_jacobian(const Problem &pb, const Params &x, Eigen::Matrix<double, 15, kNg> &J) {
  std::vector<Preintegrated> pre;
  for (int i = 0; i < kNg; ++i) {
    const double h = i < 3 ? 1e-5 : (i < 5 ? 1e-6 : (i < 8 ? 1e-6 : 1e-5));
    StateAtK s[2];
    for (int sgn = 0; sgn < 2; ++sgn) {
      VecG d = VecG::Zero();
      d(i) = sgn == 0 ? h : -h;
      const Params y = apply_step(x, d, std::vector<Vec3>(x.pf.size(), Vec3::Zero()));
      if (!pb.integrate(y.bg, y.ba, pre))
        return false;
      s[sgn] = state_at_newest(pb, y, pre);
    }
    J.block<3, 1>(0, i) = ovton::core::so3_log(s[0].R * s[1].R.transpose()) / (2 * h);
    J.block<3, 1>(3, i) = (s[0].p - s[1].p) / (2 * h);
    J.block<3, 1>(6, i) = (s[0].v - s[1].v) / (2 * h);
    J.block<3, 1>(9, i) = (s[0].bg - s[1].bg) / (2 * h);
    J.block<3, 1>(12, i) = (s[0].ba - s[1].ba) / (2 * h);
  }
  return true;
}

/// Largest sigmas of roll/pitch [deg] and of the world velocity [m/s] in a covariance of the state error.
std::pair<double, double> tilt_velocity_sigmas(const Eigen::Matrix<double, 15, 15> &P) {
  const double tilt = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(P.block<2, 2>(0, 0)).eigenvalues()(1);
  const double vel = Eigen::SelfAdjointEigenSolver<Mat3>(P.block<3, 3>(6, 6)).eigenvalues()(2);
  return {std::sqrt(std::max(0.0, tilt)) * 180.0 / M_PI, std::sqrt(std::max(0.0, vel))};
}

} // namespace

bool preintegrate(const std::deque<ImuData> &imu, int64_t t0_ns, const std::vector<int64_t> &t_ns, const Vec3 &bg,
                  const Vec3 &ba, std::vector<Preintegrated> &out) {
  out.assign(t_ns.size(), Preintegrated());
  if (imu.size() < 2 || t_ns.empty() || imu.front().t_imu_ns > t0_ns || imu.back().t_imu_ns < t_ns.back())
    return false;
  auto it = std::upper_bound(imu.begin(), imu.end(), t0_ns,
                             [](int64_t t, const ImuData &d) { return t < d.t_imu_ns; }); // first reading after t0
  ImuData a = it == imu.begin() ? *it : (it == imu.end() ? imu.back() : lerp(*(it - 1), *it, t0_ns));
  Preintegrated cur;
  for (size_t j = 0; j < t_ns.size();) {
    const int64_t target = t_ns[j];
    if (target <= a.t_imu_ns) {
      out[j++] = cur;
      continue;
    }
    const bool to_reading = it != imu.end() && it->t_imu_ns < target;
    const ImuData b = to_reading ? *it : lerp(*(it - 1), *it, target);
    const double dt = 1e-9 * static_cast<double>(b.t_imu_ns - a.t_imu_ns);
    const Vec3 w = 0.5 * (a.wm + b.wm) - bg, acc = 0.5 * (a.am + b.am) - ba;
    const Mat3 R_mid = cur.R * ovton::core::so3_exp(0.5 * dt * w);
    cur.p += cur.v * dt + 0.5 * R_mid * acc * dt * dt;
    cur.v += R_mid * acc * dt;
    cur.R = cur.R * ovton::core::so3_exp(dt * w);
    a = b;
    if (to_reading)
      ++it;
  }
  return true;
}

DynamicInitResult dynamic_initialize(const std::vector<InitFrame> &frames, const std::deque<ImuData> &imu,
                                     const Eigen::Matrix4d &T_BC, double focal_px, double gravity_mag, double sigma_yaw,
                                     double sigma_pos, double sigma_px, const DynamicInitOptions &opt) {
  DynamicInitResult res;
  const auto fail = [&](std::string why) {
    res.ok = false;
    res.why = std::move(why);
    return res;
  };
  if (frames.size() < 3)
    return fail("fewer than 3 frames in the window");

  // Features with enough observations in the window, longest tracks first.
  std::map<size_t, std::vector<std::pair<int, Vec2>>> tracks;
  for (size_t k = 0; k < frames.size(); ++k)
    for (const auto &[id, xy] : frames[k].obs)
      tracks[id].emplace_back(static_cast<int>(k), xy);
  std::vector<std::pair<size_t, size_t>> by_length; // (observations, id)
  for (const auto &[id, tr] : tracks)
    if (static_cast<int>(tr.size()) >= opt.min_observations)
      by_length.emplace_back(tr.size(), id);
  std::sort(by_length.begin(), by_length.end(),
            [](const auto &a, const auto &b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
  if (static_cast<int>(by_length.size()) > opt.max_features)
    by_length.resize(opt.max_features);
  res.features = static_cast<int>(by_length.size());
  res.frames = static_cast<int>(frames.size());
  if (res.features < opt.min_features)
    return fail("only " + std::to_string(res.features) + " features tracked through " +
                std::to_string(opt.min_observations) + " frames of the window");
  std::vector<double> disparity;
  for (const auto &[n, id] : by_length)
    disparity.push_back(focal_px * (tracks[id].back().second - tracks[id].front().second).norm());
  std::nth_element(disparity.begin(), disparity.begin() + disparity.size() / 2, disparity.end());
  res.disparity_px = disparity[disparity.size() / 2];
  if (res.disparity_px < opt.min_disparity_px)
    return fail("too little image motion (median disparity " + std::to_string(res.disparity_px) + " px)");

  const Mat3 R_BC = T_BC.block<3, 3>(0, 0);
  Problem pb{imu,
             {},
             {},
             {},
             0,
             R_BC.transpose(),
             -R_BC.transpose() * T_BC.block<3, 1>(0, 3),
             gravity_mag,
             focal_px / sigma_px};
  for (const auto &f : frames) {
    pb.t_ns.push_back(f.t_imu_ns);
    pb.t.push_back(1e-9 * static_cast<double>(f.t_imu_ns - frames.front().t_imu_ns));
  }
  for (const auto &[n, id] : by_length) {
    for (const auto &[k, xy] : tracks[id])
      pb.obs.push_back({k, pb.n_feat, xy});
    ++pb.n_feat;
  }

  Params x;
  std::vector<Preintegrated> pre;
  if (!pb.integrate(x.bg, x.ba, pre))
    return fail("IMU readings do not cover the window");
  if (!linear_start(pb, pre, x))
    return fail("degenerate linear system");

  // Levenberg-Marquardt on the Huber-weighted reprojection errors with the bias priors.
  const double k = opt.huber_px / sigma_px;
  Eigen::VectorXd r;
  pb.residuals(x, pre, r);
  double cost = total_cost(pb, r, x, k, opt.sigma_bg_prior, opt.sigma_ba_prior), lambda = 1e-3;
  Normal ne;
  for (res.iterations = 0; res.iterations < opt.max_iterations; ++res.iterations) {
    if (!build_normal(pb, x, pre, r, k, opt.sigma_bg_prior, opt.sigma_ba_prior, ne))
      return fail("IMU readings do not cover the window");
    bool improved = false;
    double rel = 1.0;
    for (int tries = 0; tries < 10 && !improved; ++tries) {
      VecG rhs;
      std::vector<Mat3> Hi;
      const MatG S = reduced(ne, lambda, &rhs, &Hi);
      const VecG dg = S.ldlt().solve(rhs);
      std::vector<Vec3> df(pb.n_feat);
      for (int f = 0; f < pb.n_feat; ++f)
        df[f] = Hi[f] * (ne.bf[f] - ne.Hgf[f].transpose() * dg);
      const Params y = apply_step(x, dg, df);
      std::vector<Preintegrated> pre_y;
      Eigen::VectorXd ry;
      if (!dg.allFinite() || !pb.integrate(y.bg, y.ba, pre_y)) {
        lambda *= 10;
        continue;
      }
      pb.residuals(y, pre_y, ry);
      const double c = total_cost(pb, ry, y, k, opt.sigma_bg_prior, opt.sigma_ba_prior);
      if (c < cost) {
        rel = (cost - c) / cost;
        x = y;
        pre = std::move(pre_y);
        r = std::move(ry);
        cost = c;
        lambda = std::max(lambda / 10, 1e-9);
        improved = true;
      } else {
        lambda *= 10;
      }
    }
    if (!improved || rel < 1e-8)
      break;
  }

  // Quality: inlier RMS, and how well gravity and velocity are determined (marginal covariance of the globals).
  double ss = 0;
  int inliers = 0;
  for (size_t i = 0; i < pb.obs.size(); ++i) {
    const double s = r.segment<2>(2 * i).norm() / pb.scale * focal_px;
    if (s < 3 * opt.huber_px) {
      ss += s * s;
      ++inliers;
    }
  }
  res.rms_px = inliers ? std::sqrt(ss / (2 * inliers)) : 1e9;
  if (!build_normal(pb, x, pre, r, k, opt.sigma_bg_prior, opt.sigma_ba_prior, ne))
    return fail("IMU readings do not cover the window");
  const MatG S = reduced(ne, 0.0, nullptr, nullptr);
  Eigen::LDLT<MatG> ldlt(S);
  if (ldlt.info() != Eigen::Success || ldlt.vectorD().minCoeff() <= 0)
    return fail("the window does not determine the state (singular information)");
  const MatG cov = ldlt.solve(MatG::Identity());
  Eigen::Matrix<double, 15, kNg> J;
  if (!state_jacobian(pb, x, J))
    return fail("IMU readings do not cover the window");
  Eigen::Matrix<double, 15, 15> P = J * cov * J.transpose();
  P = 0.5 * (P + P.transpose()).eval();
  // What the window itself determined: the same sigmas with the accelerometer bias held. Over a window with little
  // rotation a constant b_a and a tilt of gravity move every position alike (½ t² R b_a vs ½ t² δg), so the marginal
  // roll/pitch sigma cannot fall below sigma_ba_prior / g (1.2 deg for 0.2 m/s²), nor the world velocity's below
  // that times the speed, however good the images: a gate on the marginals refuses every such window. The filter
  // still gets the marginal covariance with its tilt-b_a correlation, which is what its estimate is uncertain by.
  MatG cov_given_ba = MatG::Zero();
  cov_given_ba.topLeftCorner<8, 8>() = S.topLeftCorner<8, 8>().ldlt().solve(Eigen::Matrix<double, 8, 8>::Identity());
  const Eigen::Matrix<double, 15, 15> P_given_ba = J * cov_given_ba * J.transpose();
  std::tie(res.sigma_rollpitch_deg, res.sigma_vel) = tilt_velocity_sigmas(P);
  std::tie(res.sigma_rollpitch_given_ba_deg, res.sigma_vel_given_ba) = tilt_velocity_sigmas(P_given_ba);
  const StateAtK s = state_at_newest(pb, x, pre);
  res.R_WB = s.R;
  res.p_W = s.p;
  res.v_W = s.v;
  res.bg = s.bg;
  res.ba = s.ba;
  res.P = opt.sigma_inflation * opt.sigma_inflation * P;
  res.P(2, 2) += sigma_yaw * sigma_yaw;
  res.P.block<3, 3>(3, 3) += sigma_pos * sigma_pos * Mat3::Identity();
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "%d features over %d frames (%.2f s), %d iterations, rms %.2f px, sigma roll/pitch %.2f deg "
                "(%.2f with b_a held), velocity %.3f m/s (%.3f), |v| %.3f m/s, disparity %.1f px",
                res.features, res.frames, pb.t.back(), res.iterations, res.rms_px, res.sigma_rollpitch_deg,
                res.sigma_rollpitch_given_ba_deg, res.sigma_vel, res.sigma_vel_given_ba, res.v_W.norm(),
                res.disparity_px);
  res.why = buf;
  if (res.rms_px > opt.max_rms_px)
    return fail("reprojection rms too large: " + res.why);
  if (static_cast<double>(inliers) < 0.8 * static_cast<double>(pb.obs.size()))
    return fail("too many outliers (" + std::to_string(pb.obs.size() - inliers) + " of " +
                std::to_string(pb.obs.size()) + "): " + res.why);
  if (res.sigma_rollpitch_given_ba_deg > opt.max_sigma_rollpitch_deg || res.sigma_vel_given_ba > opt.max_sigma_vel)
    return fail("not determined well enough yet: " + res.why);
  res.ok = true;
  return res;
}

} // namespace ovton::msckf
