// The fit of camera_imu_calib.h: coarse t_d grid on rotation rates, then Levenberg-Marquardt on the features.
#include "ov_core/math/so3.h"
#include "ov_core/types/errors.h"
#include "ov_core/types/imu_buffer.h"
#include "ov_msckf_ton/calib/camera_imu_calib.h"
#include "ov_msckf_ton/init/td_search_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>

namespace ovton::msckf {

using ovton::core::so3_exp;
using ovton::core::so3_log;
/// (δφ, f, t_d, t_r, gyro bias): the gyro's bias turns every pair's rotation by b·Δt, which the other parameters
/// would otherwise absorb (a 0.01 rad/s bias is 0.2 px per 30 Hz pair at f = 500).
constexpr int kP = 9;
using Vec6 = Eigen::Matrix<double, kP, 1>;
using Mat6 = Eigen::Matrix<double, kP, kP>;

CalibModel parse_calib_model(const std::string &s) {
  if (s == "rotation")
    return CalibModel::Rotation;
  if (s == "epipolar")
    return CalibModel::Epipolar;
  throw ovton::core::UsageError("calibration model must be rotation or epipolar, not '" + s + "'");
}

std::string to_string(CalibModel m) {
  return m == CalibModel::Rotation ? "rotation" : "epipolar";
}

namespace {

/// Parameters: x = (δφ [rad, IMU frame, R_IC = Exp(δφ)·R0], f [px], t_d [s], t_r [s], b_g [rad/s]).
struct Params {
  Eigen::Matrix3d R0;
  Vec6 x;
  Eigen::Matrix3d R_IC() const { return so3_exp(x.head<3>()) * R0; }
};

/// Shared inputs of the fit; times in seconds after the first image (camera clock).
struct Problem {
  const std::vector<CalibPair> *pairs;
  std::vector<size_t> used; ///< indices of the pairs in the fine fit
  const std::vector<ovton::core::ImuData> *imu;
  int64_t t0_ns;
  int width, height;
  double cu, cv;
  CalibModel model;
  double huber_px;
};

/// Rotation R_{I(a) I(b)} for a feature: the pair's rotation between its middle-row instants, turned at both ends by
/// the gyro over the rows' shifts (first order: the shifts are a few ms).
struct PairRotation {
  Eigen::Matrix3d R_ab;
  Eigen::Vector3d w_a, w_b;
};

bool pair_rotation(const Problem &p, const CalibPair &q, double td, const Eigen::Vector3d &bias, PairRotation &out) {
  const int64_t a = q.t0_cam_ns + static_cast<int64_t>(std::llround(td * 1e9));
  const int64_t b = q.t1_cam_ns + static_cast<int64_t>(std::llround(td * 1e9));
  const auto R = ovton::core::imu_rotation(*p.imu, a, b, bias);
  if (!R)
    return false;
  out.R_ab = *R;
  out.w_a = ovton::core::imu_gyro_at(*p.imu, static_cast<double>(a)) - bias;
  out.w_b = ovton::core::imu_gyro_at(*p.imu, static_cast<double>(b)) - bias;
  return true;
}

/// Residuals [px] of one pair at parameters x, appended to r (a pair the IMU does not cover gives large constant
/// residuals rather than none, so that the residual count never changes between evaluations).
void pair_residuals(const Problem &p, const CalibPair &q, const Params &par, std::vector<double> &r) {
  const double f = par.x(3), td = par.x(4), tr = par.x(5);
  PairRotation pr;
  const size_t n = q.uv0.size();
  const bool ok = pair_rotation(p, q, td, par.x.tail<3>(), pr);
  if (!ok) {
    r.insert(r.end(), p.model == CalibModel::Rotation ? 2 * n : n, 100.0);
    return;
  }
  const Eigen::Matrix3d R_IC = par.R_IC();
  const double H = p.height;
  thread_local std::vector<Eigen::Vector3d> pred, obs;
  pred.resize(n);
  obs.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const double sa = tr * (q.uv0[k].y() / H - 0.5), sb = tr * (q.uv1[k].y() / H - 0.5);
    const Eigen::Matrix3d R_I = so3_exp(-pr.w_a * sa) * pr.R_ab * so3_exp(pr.w_b * sb);
    const Eigen::Vector3d b1((q.uv1[k].x() - p.cu) / f, (q.uv1[k].y() - p.cv) / f, 1.0);
    pred[k] = R_IC.transpose() * (R_I * (R_IC * b1));
    obs[k] = Eigen::Vector3d((q.uv0[k].x() - p.cu) / f, (q.uv0[k].y() - p.cv) / f, 1.0);
  }
  if (p.model == CalibModel::Rotation) {
    for (size_t k = 0; k < n; ++k) {
      const double z = std::max(pred[k].z(), 1e-3);
      r.push_back(f * pred[k].x() / z + p.cu - q.uv0[k].x());
      r.push_back(f * pred[k].y() / z + p.cv - q.uv0[k].y());
    }
    return;
  }
  // Epipolar: b0 lies in the plane of the translation t and the rotated b1; t is the direction most orthogonal to
  // every n_k = b0 × R b1 (the smallest eigenvector), its sign fixed so that numeric derivatives do not see it flip.
  // Reweighted twice (Huber on the residual it gives), so that a few bad tracks do not turn t.
  thread_local std::vector<double> w;
  w.assign(n, 1.0);
  Eigen::Vector3d t = Eigen::Vector3d::UnitZ();
  const auto residual = [&](size_t k) {
    const Eigen::Vector3d m = t.cross(pred[k].normalized());
    return f * obs[k].normalized().dot(m) / std::max(m.norm(), 0.05);
  };
  for (int pass = 0; pass < 3; ++pass) {
    Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
    for (size_t k = 0; k < n; ++k) {
      const Eigen::Vector3d nk = obs[k].normalized().cross(pred[k].normalized());
      M += w[k] * nk * nk.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(M);
    t = es.eigenvectors().col(0);
    Eigen::Index big;
    t.cwiseAbs().maxCoeff(&big);
    if (t(big) < 0)
      t = -t;
    for (size_t k = 0; pass < 2 && k < n; ++k) {
      const double e = std::abs(residual(k));
      w[k] = e <= p.huber_px ? 1.0 : p.huber_px / e;
    }
  }
  for (size_t k = 0; k < n; ++k)
    r.push_back(residual(k));
}

std::vector<double> residuals(const Problem &p, const Params &par, std::vector<size_t> *pair_end = nullptr) {
  std::vector<double> r;
  if (pair_end)
    pair_end->clear();
  for (size_t i : p.used) {
    pair_residuals(p, (*p.pairs)[i], par, r);
    if (pair_end)
      pair_end->push_back(r.size());
  }
  return r;
}

double huber_weight(double e, double c) {
  return std::abs(e) <= c ? 1.0 : c / std::abs(e);
}

double robust_cost(const std::vector<double> &r, double c) {
  double s = 0;
  for (double e : r)
    s += std::abs(e) <= c ? 0.5 * e * e : c * (std::abs(e) - 0.5 * c);
  return s;
}

/// Per pair: the camera's rotation rate from its bearings at focal f (rotation-only Kabsch, Huber), camera frame.
std::vector<PairRate> camera_rates(const Problem &p, const std::vector<size_t> &idx, double f) {
  std::vector<PairRate> out;
  std::vector<Eigen::Vector3d> a, c;
  for (size_t i : idx) {
    const CalibPair &q = (*p.pairs)[i];
    a.clear();
    c.clear();
    for (size_t k = 0; k < q.uv0.size(); ++k) {
      a.push_back(Eigen::Vector3d((q.uv0[k].x() - p.cu) / f, (q.uv0[k].y() - p.cv) / f, 1).normalized());
      c.push_back(Eigen::Vector3d((q.uv1[k].x() - p.cu) / f, (q.uv1[k].y() - p.cv) / f, 1).normalized());
    }
    const double t0 = ovton::core::ns_to_s(q.t0_cam_ns - p.t0_ns), t1 = ovton::core::ns_to_s(q.t1_cam_ns - p.t0_ns);
    out.push_back({t0, t1, so3_log(fit_rotation(a, c, 2.0 / f)) / (t1 - t0)});
  }
  return out;
}

/// R with w_I ≈ R·w_C (Wahba, Huber-reweighted); returns the trimmed mean of the squared residuals (lowest 80 %).
double fit_rate_rotation(const std::vector<Eigen::Vector3d> &wI, const std::vector<Eigen::Vector3d> &wC,
                         Eigen::Matrix3d &R) {
  std::vector<double> w(wI.size(), 1.0), e2(wI.size());
  for (int it = 0; it < 4; ++it) {
    Eigen::Matrix3d B = Eigen::Matrix3d::Zero();
    for (size_t k = 0; k < wI.size(); ++k)
      B += w[k] * wI[k] * wC[k].transpose();
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(B, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
    R = svd.matrixU() * D * svd.matrixV().transpose();
    for (size_t k = 0; k < wI.size(); ++k)
      e2[k] = (wI[k] - R * wC[k]).squaredNorm();
    std::vector<double> s = e2;
    std::nth_element(s.begin(), s.begin() + s.size() / 2, s.end());
    const double c = 2.0 * std::sqrt(s[s.size() / 2]) + 1e-9;
    for (size_t k = 0; k < wI.size(); ++k)
      w[k] = huber_weight(std::sqrt(e2[k]), c);
  }
  std::sort(e2.begin(), e2.end());
  const size_t keep = std::max<size_t>(1, e2.size() * 8 / 10);
  double sum = 0;
  for (size_t k = 0; k < keep; ++k)
    sum += e2[k];
  return sum / static_cast<double>(keep);
}

/// The coarse stage: every candidate t_d with R_IC in closed form; fills res.coarse_*, returns the best t_d and R0.
double coarse_search(const Problem &p, const std::vector<size_t> &idx, double f, const CalibOptions &opt,
                     CalibResult &res, Eigen::Matrix3d &R_best) {
  const std::vector<PairRate> rates = camera_rates(p, idx, f);
  const ovton::core::GyroIntegral gyro(*p.imu, p.t0_ns);
  const int n = static_cast<int>(std::floor(opt.td_range_s / opt.td_step_s));
  double best = 1e300, best_td = opt.td_prior_s;
  std::vector<Eigen::Vector3d> wI, wC;
  for (int k = -n; k <= n; ++k) {
    const double td = opt.td_prior_s + k * opt.td_step_s;
    wI.clear();
    wC.clear();
    for (const auto &q : rates) {
      if (q.t0 + td < gyro.begin() || q.t1 + td > gyro.end())
        continue;
      wI.push_back(gyro.mean(q.t0 + td, q.t1 + td));
      wC.push_back(q.w);
    }
    Eigen::Matrix3d R;
    const double cost = wI.size() >= 20 ? fit_rate_rotation(wI, wC, R) : 1e300;
    res.coarse_profile.push_back(cost);
    if (cost < best) {
      best = cost;
      best_td = td;
      R_best = R;
    }
  }
  if (best >= 1e300)
    throw ovton::core::DataError("calibrate", "the IMU log does not cover the images at any candidate offset");
  return best_td;
}

/// Numeric Jacobian (central differences), N x kP.
Eigen::MatrixXd jacobian(const Problem &p, const Params &par, const Vec6 &step) {
  const std::vector<double> r0 = residuals(p, par);
  Eigen::MatrixXd J(r0.size(), kP);
  for (int j = 0; j < kP; ++j) {
    Params a = par, b = par;
    a.x(j) += step(j);
    b.x(j) -= step(j);
    const std::vector<double> ra = residuals(p, a), rb = residuals(p, b);
    for (size_t i = 0; i < r0.size(); ++i)
      J(static_cast<Eigen::Index>(i), j) = (ra[i] - rb[i]) / (2 * step(j));
  }
  return J;
}

/// Sandwich covariance: H⁻¹ S H⁻¹ with S the pairs' score sums, Bartlett-weighted over `lag` neighbouring pairs.
Mat6 sandwich(const Eigen::MatrixXd &J, const std::vector<double> &r, const std::vector<double> &w,
              const std::vector<size_t> &pair_end, int lag, const Eigen::Array<bool, kP, 1> &free) {
  Mat6 H = Mat6::Zero();
  std::vector<Vec6> g(pair_end.size(), Vec6::Zero());
  size_t b = 0;
  for (size_t k = 0; k < pair_end.size(); ++k) {
    for (size_t i = b; i < pair_end[k]; ++i) {
      const Vec6 Ji = J.row(static_cast<Eigen::Index>(i)).transpose();
      H += w[i] * Ji * Ji.transpose();
      g[k] += w[i] * r[i] * Ji;
    }
    b = pair_end[k];
  }
  Mat6 S = Mat6::Zero();
  for (size_t k = 0; k < g.size(); ++k) {
    S += g[k] * g[k].transpose();
    for (int l = 1; l <= lag && k + l < g.size(); ++l) {
      const double wl = 1.0 - static_cast<double>(l) / (lag + 1);
      S += wl * (g[k] * g[k + l].transpose() + g[k + l] * g[k].transpose());
    }
  }
  for (int j = 0; j < kP; ++j)
    if (!free(j)) {
      H.row(j).setZero();
      H.col(j).setZero();
      H(j, j) = 1.0;
      S.row(j).setZero();
      S.col(j).setZero();
    }
  const Mat6 Hi = H.inverse();
  return Hi * S * Hi;
}

/// Levenberg-Marquardt with Huber IRLS weights from `par` on; returns the iterations made.
int levenberg_marquardt(const Problem &p, Params &par, const Eigen::Array<bool, kP, 1> &free, const Vec6 &step,
                        int max_iterations, double huber_px) {
  double lambda = 1e-3;
  int iterations = 0;
  std::vector<double> r = residuals(p, par), w(r.size(), 1.0);
  for (int it = 0; it < max_iterations; ++it) {
    iterations = it + 1;
    for (size_t i = 0; i < r.size(); ++i)
      w[i] = huber_weight(r[i], huber_px);
    const Eigen::MatrixXd J = jacobian(p, par, step);
    Mat6 H = Mat6::Zero();
    Vec6 g = Vec6::Zero();
    for (Eigen::Index i = 0; i < J.rows(); ++i) {
      H += w[i] * J.row(i).transpose() * J.row(i);
      g += w[i] * r[i] * J.row(i).transpose();
    }
    for (int j = 0; j < kP; ++j)
      if (!free(j)) {
        H.row(j).setZero();
        H.col(j).setZero();
        H(j, j) = 1.0;
        g(j) = 0;
      }
    const double cost0 = robust_cost(r, huber_px);
    bool improved = false;
    for (int tries = 0; tries < 8 && !improved; ++tries) {
      Mat6 A = H;
      A.diagonal() += lambda * H.diagonal();
      const Vec6 dx = -A.ldlt().solve(g);
      Params cand = par;
      cand.x += dx;
      const std::vector<double> rc = residuals(p, cand);
      if (robust_cost(rc, huber_px) < cost0) {
        improved = true;
        par = cand;
        r = rc;
        lambda = std::max(lambda / 4, 1e-7);
        if (dx.head<3>().norm() < 1e-6 && std::abs(dx(3)) < 1e-3 && std::abs(dx(4)) < 1e-6 && std::abs(dx(5)) < 1e-6 &&
            dx.tail<3>().norm() < 1e-6)
          return iterations;
      } else {
        lambda *= 8;
      }
    }
    if (!improved)
      break;
  }
  return iterations;
}

/// Delete-one-block jackknife over `blocks` contiguous stretches of the used pairs: each refit (from the full
/// solution) leaves one stretch out; the spread of the refits is the estimate's σ wherever the model's error varies
/// along the recording (translation absorbed differently, a moving offset), which a per-residual σ cannot see.
Vec6 jackknife_sigma(const Problem &p, const Params &full, const Eigen::Array<bool, kP, 1> &free, const Vec6 &step,
                     int blocks, double huber_px, std::vector<Vec6> &fits) {
  fits.clear();
  const size_t n = p.used.size();
  for (int k = 0; k < blocks; ++k) {
    Problem q = p;
    q.used.clear();
    for (size_t i = 0; i < n; ++i)
      if (static_cast<int>(i * static_cast<size_t>(blocks) / n) != k)
        q.used.push_back(p.used[i]);
    Params par = full;
    levenberg_marquardt(q, par, free, step, 15, huber_px);
    Vec6 x = par.x;
    // The rotation as an error against the full fit's, so that the spread is in the same tangent space.
    x.head<3>() = so3_log(par.R_IC() * full.R_IC().transpose());
    fits.push_back(x);
  }
  Vec6 mean = Vec6::Zero();
  for (const auto &x : fits)
    mean += x / blocks;
  Vec6 var = Vec6::Zero();
  for (const auto &x : fits)
    var += (x - mean).cwiseProduct(x - mean);
  return (var * (blocks - 1.0) / blocks).cwiseSqrt();
}

} // namespace

CalibResult calibrate_camera_imu(const std::vector<CalibPair> &pairs, const std::vector<ovton::core::ImuData> &imu,
                                 int width, int height, const CalibOptions &opt, const std::string &source) {
  const auto t_start = std::chrono::steady_clock::now();
  CalibResult res;
  res.width = width;
  res.height = height;
  res.cu = 0.5 * width;
  res.cv = 0.5 * height;
  res.focal_prior_px = 0.5 * width / std::tan(0.5 * opt.hfov_prior_deg * M_PI / 180.0);
  res.readout_estimated = opt.estimate_readout;
  res.pairs_total = static_cast<int>(pairs.size());
  if (imu.size() < 10 || pairs.empty())
    throw ovton::core::DataError(source, "too few images or IMU readings to calibrate from");
  Problem p{&pairs, {}, &imu, pairs.front().t0_cam_ns, width, height, res.cu, res.cv, opt.model, opt.huber_px};
  std::vector<size_t> usable;
  for (size_t i = 0; i < pairs.size(); ++i)
    if (static_cast<int>(pairs[i].uv0.size()) >= opt.min_features_per_pair && pairs[i].t1_cam_ns > pairs[i].t0_cam_ns)
      usable.push_back(i);
  if (usable.size() < 30)
    throw ovton::core::DataError(source, "only " + std::to_string(usable.size()) + " image pairs share at least " +
                                             std::to_string(opt.min_features_per_pair) +
                                             " tracked features: too few to calibrate from");
  Eigen::Matrix3d R0;
  res.coarse_td_s = coarse_search(p, usable, res.focal_prior_px, opt, res, R0);
  res.coarse_R_IC = R0;
  double f_start = res.focal_prior_px, td_start = res.coarse_td_s, tr_start = 0;
  if (opt.has_start) {
    R0 = opt.start_R_IC;
    f_start = opt.start_focal_px;
    td_start = opt.start_td_s;
    tr_start = opt.start_readout_s;
  }

  // The fine fit keeps the pairs that rotate at the coarse offset (a still pair only shows parallax).
  for (size_t i : usable) {
    PairRotation pr;
    if (pair_rotation(p, pairs[i], td_start, Eigen::Vector3d::Zero(), pr) &&
        so3_log(pr.R_ab).norm() >= opt.min_pair_rotation_rad)
      p.used.push_back(i);
  }
  if (p.used.size() < 30)
    throw ovton::core::DataError(source, "only " + std::to_string(p.used.size()) + " image pairs rotate by more than " +
                                             std::to_string(opt.min_pair_rotation_rad) + " rad: too little rotation");
  Params par{R0, Vec6::Zero()};
  par.x << 0, 0, 0, f_start, td_start, tr_start, 0, 0, 0;
  Eigen::Array<bool, kP, 1> free;
  free << true, true, true, true, true, opt.estimate_readout, true, true, true;
  Vec6 step;
  step << 1e-4, 1e-4, 1e-4, 0.05, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4;
  res.iterations = levenberg_marquardt(p, par, free, step, opt.max_iterations, opt.huber_px);
  std::vector<double> r, w;
  // Covariance at the solution.
  std::vector<size_t> pair_end;
  r = residuals(p, par, &pair_end);
  w.assign(r.size(), 1.0);
  for (size_t i = 0; i < r.size(); ++i)
    w[i] = huber_weight(r[i], opt.huber_px);
  const Mat6 C = sandwich(jacobian(p, par, step), r, w, pair_end, opt.sigma_lag_pairs, free);
  res.robust_cost = robust_cost(r, opt.huber_px);
  res.R_IC = par.R_IC();
  res.focal_px = par.x(3);
  res.td_s = par.x(4);
  res.readout_s = opt.estimate_readout ? par.x(5) : 0.0;
  Vec6 sd = C.diagonal().cwiseMax(0).cwiseSqrt();
  for (int i = 0; i < 6; ++i) // the sandwich's correlations (the jackknife's 8 refits are too few for them)
    for (int j = 0; j < 6; ++j)
      res.correlation(i, j) = sd(i) > 0 && sd(j) > 0 ? C(i, j) / (sd(i) * sd(j)) : (i == j ? 1.0 : 0.0);
  res.sigma_sandwich.setZero();
  res.sigma_sandwich << sd.head<3>().norm(), sd(3), sd(4), sd(5);
  if (opt.jackknife_blocks >= 2) {
    std::vector<Vec6> fits;
    const Vec6 jk = jackknife_sigma(p, par, free, step, opt.jackknife_blocks, opt.huber_px, fits);
    res.sigma_jackknife << jk.head<3>().norm(), jk(3), jk(4), jk(5);
    sd = sd.cwiseMax(jk);
    for (const auto &x : fits)
      res.jackknife_td_s.push_back(x(4));
  }
  res.sigma_rot_rad = sd.head<3>();
  res.sigma_focal_px = sd(3);
  res.sigma_td_s = sd(4);
  res.sigma_readout_s = sd(5);
  res.gyro_bias = par.x.tail<3>();
  res.sigma_gyro_bias = sd.tail<3>();
  res.pairs_used = static_cast<int>(p.used.size());
  double ss = 0;
  long n_in = 0, n_rms = 0;
  for (double e : r) {
    n_in += std::abs(e) <= opt.huber_px;
    if (std::abs(e) <= 3 * opt.huber_px) {
      ss += e * e;
      ++n_rms;
    }
  }
  res.features_used = 0;
  for (size_t i : p.used)
    res.features_used += static_cast<long>(pairs[i].uv0.size());
  res.rms_px = n_rms > 0 ? std::sqrt(ss / n_rms) : 0.0;
  res.inlier_share = r.empty() ? 0.0 : static_cast<double>(n_in) / static_cast<double>(r.size());
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return res;
}

} // namespace ovton::msckf
