#include "ov_eval/diagnose/rate_design.h"
#include "ov_core/math/so3.h"
#include "ov_core/types/imu_buffer.h"
#include "ov_eval/diagnose/candidates.h"
#include "ov_eval/diagnose/filter_calibration.h"
#include "ov_eval/diagnose/image_geometry.h"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <iterator>
#include <map>
#include <vector>

namespace ovton::eval::diag {

using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

using Vec9 = Eigen::Matrix<double, 9, 1>;

/// One observation with neighbours on both sides in its track, and its image velocity.
struct FlowObs {
  Eigen::Vector2d x, xdot;
  double rho, inv_z;
  size_t track;
  int n_win = 0;                     ///< positions in the slope's window
  std::array<double, 5> win_t_imu{}; ///< their IMU-clock times [ns]
  std::array<double, 5> win_w{};     ///< the slope's weight on each: ẋ = Σ w_q·x_q
  double t_imu = 0;                  ///< this observation's IMU-clock time [ns]
};
using FrameMap = std::map<int64_t, std::vector<FlowObs>>; ///< by camera time

struct FlowData {
  FrameMap frames;
  size_t n_tracks = 0;
};

/// The observations of known depth with a neighbour on each side, per image, each with its image velocity: the local
/// slope of a quadratic through up to five measured positions around it (least squares). The slope is linear in the
/// positions, ẋ = Σ w_q·x_q, and the weights are kept to put the gyro through the same slope.
FlowData collect_flow(const TrackMap &tracks, const DiagnoseReport &rep) {
  FlowData fd;
  for (const auto &kv : tracks) {
    const auto &tr = kv.second;
    const size_t m = tr.size();
    for (size_t j = 1; j + 1 < m; ++j) {
      const ResidualLogRow *r = tr[j];
      if (!(std::isfinite(r->depth_m) && r->depth_m > 0))
        continue;
      const size_t a = j >= 2 ? j - 2 : 0, b = std::min(m - 1, j + 2);
      const auto h = [&](size_t q) {
        const double tau = 1e-9 * double(tr[q]->t_cam_ns - r->t_cam_ns);
        return Eigen::Vector3d(1.0, tau, tau * tau);
      };
      Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
      for (size_t q = a; q <= b; ++q)
        A += h(q) * h(q).transpose();
      const Eigen::LDLT<Eigen::Matrix3d> Al(A);
      FlowObs o{Eigen::Vector2d(r->x_norm, r->y_norm), Eigen::Vector2d::Zero(), r->v_px / rep.image_height - 0.5,
                1.0 / r->depth_m, fd.n_tracks};
      for (size_t q = a; q <= b; ++q) {
        o.win_t_imu[o.n_win] = double(tr[q]->t_cam_ns) + 1e9 * tr[q]->td_s;
        o.win_w[o.n_win] = Al.solve(h(q))(1);
        o.xdot += o.win_w[o.n_win++] * Eigen::Vector2d(tr[q]->x_norm, tr[q]->y_norm);
      }
      o.t_imu = double(r->t_cam_ns) + 1e9 * r->td_s;
      fd.frames[r->t_cam_ns].push_back(o);
    }
    ++fd.n_tracks;
  }
  return fd;
}

/// The flow model's rows for one feature: ẋ = H·(ω, ψ, v).
Eigen::Matrix<double, 2, 9> flow_rows(const Eigen::Vector2d &x, double rho, double iz) {
  Eigen::Matrix<double, 2, 9> H;
  H.leftCols<3>() = rot_flow(x.x(), x.y());
  H.middleCols<3>(3) = rho * H.leftCols<3>();
  H.rightCols<3>() << -iz, 0, x.x() * iz, 0, -iz, x.y() * iz;
  return H;
}

struct FrameFit {
  Vec9 sol, focal; ///< fitted (ω, ψ, v) and its response to a unit relative focal error
  Eigen::Matrix<double, 9, 9> C;
  VectorXd w;
  /// Without ψ: ω's response to a ψ in the data (camera frame). ω is then the rate at the features' mean row, and a
  /// readout t_r moves it by psi_resp·α·t_r, which varies with the features' rows from image to image.
  Eigen::Matrix3d psi_resp = Eigen::Matrix3d::Zero();
};
using FitMap = std::map<int64_t, FrameFit>;

/// The per-image flow fits, alternated with a correction of every track's inverse depth. The logged depths ẑ come
/// from the filter's triangulation. A filter holding a wrong offset triangulates with poses from the wrong instant,
/// and its points take up part of the offset: their depth errors would let the translational flow absorb part of the
/// rotation an offset error adds (measured: 30 ms read as 15-23 ms, docs/diagnose.md). Each track's inverse depth
/// therefore gets a correction ε_track, alternated with the per-image fits: per image (ω, ψ, v) by Huber IRLS on the
/// flow model with inverse depths 1/ẑ + ε_track, then every ε_track by weighted least squares on what the images'
/// translational flow leaves of its observations.
class FlowFitter {
public:
  explicit FlowFitter(size_t n_tracks) : eps_(n_tracks, 0.0) {}

  /// The depth correction of a track, as left by the last solve().
  double eps(size_t track) const { return eps_[track]; }

  /// One image's flow design with the current depth corrections: (ω, ψ, v), or (ω, v) without ψ.
  MatrixXd frame_design(const std::vector<FlowObs> &obs, bool with_psi) const {
    const Eigen::Index no = static_cast<Eigen::Index>(obs.size());
    MatrixXd H(2 * no, with_psi ? 9 : 6);
    for (Eigen::Index q = 0; q < no; ++q) {
      const Eigen::Matrix<double, 2, 9> Hq = flow_rows(obs[q].x, obs[q].rho, obs[q].inv_z + eps_[obs[q].track]);
      if (with_psi)
        H.middleRows<2>(2 * q) = Hq;
      else
        H.middleRows<2>(2 * q) << Hq.leftCols<3>(), Hq.rightCols<3>();
    }
    return H;
  }

  /// with_psi false: ψ fixed at 0, so ω is the rate at the features' mean row (what the ω rows compare with the gyro,
  /// with psi_resp for a readout; fitting ψ as well costs ω precision where the features do not span the rows evenly).
  FrameFit fit_frame(const std::vector<FlowObs> &obs, bool with_psi) const {
    const Eigen::Index no = static_cast<Eigen::Index>(obs.size());
    const int p = with_psi ? 9 : 6;
    const MatrixXd H = frame_design(obs, with_psi);
    VectorXd y(2 * no);
    FrameFit f;
    f.w = VectorXd::Ones(2 * no);
    for (Eigen::Index q = 0; q < no; ++q)
      y.segment<2>(2 * q) = obs[q].xdot;
    // The solution and its covariance in the 9 parameters (ψ rows and columns zero without ψ).
    const auto expand = [&](const VectorXd &v) {
      Vec9 out = Vec9::Zero();
      if (with_psi)
        out = v;
      else
        out << v.head<3>(), Eigen::Vector3d::Zero(), v.tail<3>();
      return out;
    };
    double s2 = 0;
    Eigen::LDLT<MatrixXd> N;
    for (int it = 0; it < 3; ++it) { // Huber IRLS, scale from the previous pass
      const MatrixXd Hw = f.w.asDiagonal() * H;
      N.compute(H.transpose() * Hw);
      const VectorXd sol = N.solve(Hw.transpose() * y);
      f.sol = expand(sol);
      const VectorXd e = y - H * sol;
      std::vector<double> ae(e.size());
      for (Eigen::Index q = 0; q < e.size(); ++q)
        ae[q] = std::abs(e(q));
      const double sc = std::max(1e-12, 1.4826 * median(ae));
      s2 = sc * sc;
      for (Eigen::Index q = 0; q < e.size(); ++q)
        f.w(q) = std::abs(e(q)) <= 3 * sc ? 1.0 : 3 * sc / std::abs(e(q));
    }
    const MatrixXd Hw = f.w.asDiagonal() * H;
    N.compute(H.transpose() * Hw);
    const MatrixXd C = s2 * N.solve(MatrixXd::Identity(p, p));
    if (!with_psi) {
      MatrixXd Hpsi(2 * no, 3);
      for (Eigen::Index q = 0; q < no; ++q)
        Hpsi.middleRows<2>(2 * q) = obs[q].rho * rot_flow(obs[q].x.x(), obs[q].x.y());
      f.psi_resp = N.solve(Hw.transpose() * Hpsi).topRows<3>();
    }
    f.C.setZero();
    for (int a = 0; a < p; ++a)
      f.C.col(with_psi || a < 3 ? a : a + 3) = expand(C.col(a));
    return f;
  }

  /// Alternates the fits and the depth corrections (from zero). fits: without ψ, images with 12+ features;
  /// fits_psi: with ψ, images with 20+.
  void solve(const FrameMap &data, FitMap &fits, FitMap &fits_psi) {
    std::fill(eps_.begin(), eps_.end(), 0.0);
    const int n_alternations = 10; // measured: 10 and 30 give the same estimates within a tenth of their SE
    for (int outer = 0; outer <= n_alternations; ++outer) {
      const bool last = outer == n_alternations;
      fits_psi.clear();
      for (const auto &[t_cam, obs] : data) {
        if (obs.size() >= 12 && last)
          fits[t_cam] = fit_frame(obs, false);
        if (obs.size() >= 20) // ψ needs features spread over the rows
          fits_psi[t_cam] = fit_frame(obs, true);
        else if (obs.size() >= 12 && !last)
          fits_psi[t_cam] = fit_frame(obs, false);
      }
      if (last)
        break;
      // ε per track: least squares of what the translational flow leaves, given every image's (ω, ψ, v). With ψ: a
      // rolling shutter's row-dependent flow would otherwise go into the depths of tracks at different rows.
      std::vector<double> num(eps_.size(), 0.0), den(eps_.size(), 0.0);
      for (const auto &[t_cam, f] : fits_psi) {
        const auto &obs = data.at(t_cam);
        for (size_t q = 0; q < obs.size(); ++q) {
          const auto &o = obs[q];
          const Eigen::Vector3d v = f.sol.tail<3>();
          const Eigen::Vector2d a(-v.x() + o.x.x() * v.z(), -v.y() + o.x.y() * v.z());
          const Eigen::Vector2d d = o.xdot - flow_rows(o.x, o.rho, o.inv_z) * f.sol;
          const Eigen::Vector2d w = f.w.segment<2>(2 * q);
          num[o.track] += w.dot(a.cwiseProduct(d));
          den[o.track] += w.dot(a.cwiseAbs2());
        }
      }
      for (size_t k = 0; k < eps_.size(); ++k)
        eps_[k] = den[k] > 0 ? num[k] / den[k] : 0.0;
    }
  }

private:
  std::vector<double> eps_;
};

/// The focal column: how ω responds to a relative focal error ε, through the whole fit (depth corrections included),
/// into fits[·].focal. A focal error moves a measured point to x_m = x + ε·s(x) (s: focal_dir) and its velocity by
/// ε·J_s·ẋ, and the fit evaluates the model at x_m: to first order the data change by ε·(J_s·F − J_F·s), F the fitted
/// flow at x. The data are perturbed by that for a step ε = kappa and fitted again. Only ω's response is used: with
/// ψ's as well, a noise-free 1 % focal error read 0.80 % (without, 1.04 %; docs/diagnose.md). Leaves the fitter with
/// the perturbed data's depth corrections.
void add_focal_response(const FrameMap &frames, const ovton::core::CameraModel &cam, FlowFitter &fitter, FitMap &fits,
                        const FitMap &fits_psi,
                        const std::function<Eigen::Vector3d(int64_t, const FrameFit &)> &omega_bar,
                        const std::map<int64_t, Eigen::Vector3d> &omega_bar0, double kappa) {
  const double h = 1e-5;
  FrameMap perturbed = frames;
  for (auto &[t_cam, obs] : perturbed) {
    const FrameFit *fit = fits_psi.count(t_cam) ? &fits_psi.at(t_cam) : fits.count(t_cam) ? &fits.at(t_cam) : nullptr;
    if (!fit)
      continue;
    for (auto &o : obs) {
      const double iz = o.inv_z + fitter.eps(o.track);
      const auto F = [&](const Eigen::Vector2d &x) -> Eigen::Vector2d { return flow_rows(x, o.rho, iz) * fit->sol; };
      const Eigen::Vector2d Fx = F(o.x), s = focal_dir(&cam, o.x);
      const Eigen::Vector2d JsF = (focal_dir(&cam, o.x + h * Fx) - focal_dir(&cam, o.x - h * Fx)) / (2 * h);
      const Eigen::Vector2d JFs = (F(o.x + h * s) - F(o.x - h * s)) / (2 * h);
      o.xdot += kappa * (JsF - JFs);
    }
  }
  FitMap fits_p, fits_psi_p;
  fitter.solve(perturbed, fits_p, fits_psi_p);
  for (auto &[t_cam, f] : fits) {
    const auto p = fits_p.find(t_cam);
    f.focal = p != fits_p.end() ? ((p->second.sol - f.sol) / kappa).eval() : Vec9::Zero();
    // ω̄_gyro moves too: it takes the fit's velocity and depths (GyroThroughImages).
    if (p != fits_p.end())
      f.focal.head<3>() -= (omega_bar(t_cam, p->second) - omega_bar0.at(t_cam)) / kappa;
  }
}

/// ω̄_gyro: the gyro put through the images' whole estimator — every feature of an image, at its corrected depth,
/// moved by the gyro's rotation and the image's fitted velocity to each image of its slope window (perspective
/// included), the same slope, the same per-image fit with the same weights. The translation is there because the
/// slope's distortion of combined rotation and translation is not that of rotation alone: without it, true poses
/// and noise-free tracks read a 0.16-0.20 % gyro scale on the agile flights (now 0.00 %; docs/diagnose.md,
/// "Translation in ω̄"). The focal is compared with it: the slope of a quadratic through ±100 ms
/// distorts fast rotation, and the raw gyro made V1_03's oracle run read a 3 % gyro "scale error" and a 0.9 % focal
/// error; the gyro's rotation angle through the slope alone (no perspective) still left 0.46 % (docs/diagnose.md).
/// Every ω row compares with it since session 30 (the time candidates had kept the raw gyro at the image's instant,
/// α a ±50 ms difference of it: docs/diagnose.md, "One set of ω rows").
class GyroThroughImages {
public:
  explicit GyroThroughImages(const std::vector<ovton::core::ImuData> &imu) : imu_(imu) {}

  /// In the camera frame, for the image with features `obs` fitted as `ff` (the fitter's current depth corrections),
  /// the camera-body rotation R_BC the filter held at the image.
  Eigen::Vector3d omega(const std::vector<FlowObs> &obs, const FrameFit &ff, const FlowFitter &fitter,
                        const Eigen::Matrix3d &R_BC) {
    const Eigen::Index no = static_cast<Eigen::Index>(obs.size());
    const MatrixXd H = fitter.frame_design(obs, false);
    VectorXd y(2 * no);
    const Eigen::Vector3d v = ff.sol.tail<3>(); // the camera's velocity over depth units, as the images show it
    for (Eigen::Index q = 0; q < no; ++q) {
      const FlowObs &o = obs[q];
      Eigen::Vector2d xdot = Eigen::Vector2d::Zero();
      const double iz = o.inv_z + fitter.eps(o.track);
      for (int k = 0; k < o.n_win; ++k) {
        const Eigen::Matrix3d R_CjCq = R_BC.transpose() * R_BjBq(o.t_imu, o.win_t_imu[k]) * R_BC;
        // The point at its corrected depth, seen from where the fitted velocity takes the camera by image k.
        const Eigen::Vector3d P =
            iz > 0 ? (o.x.homogeneous() / iz - 1e-9 * (o.win_t_imu[k] - o.t_imu) * v).eval() : o.x.homogeneous();
        const Eigen::Vector3d b = R_CjCq.transpose() * P;
        xdot += o.win_w[k] * b.head<2>() / b.z();
      }
      y.segment<2>(2 * q) = xdot;
    }
    const MatrixXd Hw = ff.w.asDiagonal() * H;
    return (H.transpose() * Hw).ldlt().solve(Hw.transpose() * y).head<3>();
  }

private:
  /// The body's rotation from IMU time t0 to t1, integrated from the gyro (memoised: windows overlap).
  const Eigen::Matrix3d &R_BjBq(double t0, double t1) {
    auto it = cache_.find({t0, t1});
    if (it != cache_.end())
      return it->second;
    return cache_.emplace(std::make_pair(t0, t1), body_rotation(imu_, t0, t1)).first->second;
  }

  const std::vector<ovton::core::ImuData> &imu_;
  std::map<std::pair<double, double>, Eigen::Matrix3d> cache_;
};

/// The angular acceleration the images' ψ and ω rows are compared with: the gyro through the images' slope. A feature's
/// velocity is the slope Σ_q w_q·x_q of its track's positions, and under a rolling shutter the position at image q is
/// exposed ρ·t_r later at row ρ, so the images' rate changes down the image by ψ = t_r·Σ_q w_q·ω(t_q): the same slope
/// taken of the camera's rate. The regressor is that slope of the gyro's rate, ω(t_q) its mean over one image interval
/// around t_q (the images, one per interval, cannot follow faster motion), averaged over the image's features, each
/// with its own window. The gyro's difference over ±50 ms that this replaced carries the gyro's vibration, which the
/// images do not see (the IMU model measured on the real V1_01 log: 10-100 Hz bands; on the agile flight 0.63 rad/s²
/// RMS of it on the body y axis against 0.81 of signal); an error in the regressor scales the estimate by var(α) /
/// (var(α) + var(error)): with the true poses a 20 ms readout read 16.1 ms (body axes 0.95, 0.62, 0.77 of it;
/// noise-free tracks 17.0 ms), now 19.2 ms (noise-free 20.1 ms).
class GyroSlope {
public:
  explicit GyroSlope(const std::vector<ovton::core::ImuData> &imu)
      : t0_ns_(imu.empty() ? 0 : imu.front().t_imu_ns), angle_(imu, t0_ns_) {}

  /// α for an image with features `obs` (their windows' IMU times and slope weights), images interval_ns apart.
  Eigen::Vector3d alpha(const std::vector<FlowObs> &obs, double interval_ns) const {
    Eigen::Vector3d a = Eigen::Vector3d::Zero();
    for (const FlowObs &o : obs)
      for (int k = 0; k < o.n_win; ++k)
        a += o.win_w[k] * (angle_at(o.win_t_imu[k] + 0.5 * interval_ns) - angle_at(o.win_t_imu[k] - 0.5 * interval_ns));
    return a / (1e-9 * interval_ns * double(std::max<size_t>(1, obs.size())));
  }

private:
  /// The gyro's integral up to IMU time t [rad] (the rate held at the ends).
  Eigen::Vector3d angle_at(double t_ns) const { return angle_.integral(1e-9 * (t_ns - double(t0_ns_))); }

  int64_t t0_ns_;
  ovton::core::GyroIntegral angle_;
};

/// The images' interval: the median step between the camera times of the flow data [ns].
double image_interval_ns(const FrameMap &frames) {
  std::vector<double> steps;
  for (auto it = frames.begin(); it != frames.end() && std::next(it) != frames.end(); ++it)
    steps.push_back(double(std::next(it)->first - it->first));
  return steps.empty() ? 50e6 : median(steps);
}

/// One image's rates, in the body frame.
struct FrameRate {
  double t;                    ///< s from t_first
  Eigen::Vector3d alpha, se;   ///< α, the gyro through the images' slope (GyroSlope); SE of ω_vis
  Eigen::Vector3d alpha_row;   ///< what a unit readout time moves ω_vis by (FrameFit::psi_resp·α, body frame)
  Eigen::Vector3d psi, psi_se; ///< ψ_vis (body frame) and its SE
  Eigen::Vector3d focal_e;     ///< response of ω_vis to a unit relative focal error
  Eigen::Vector3d gyro_s, e_s; ///< ω̄_gyro, the gyro through the images' estimator, and ω_vis − ω̄_gyro
};

/// The gyro's linear error columns beyond the isotropic scale, on ω_vis − ω̄_gyro (body frame), in the order
/// kGyroAxY, kGyroAxZ, kExtRot0..2, kGyroMis0..2: the gyro reads (I + M)·ω, so the mismatch is −M·ω̄; a camera-body
/// rotation φ (R_BC true = Exp(φ)·R_BC) makes R_BC·ω_vis = ω − φ × ω, a mismatch ω̄ × φ; M's symmetric off-diagonal
/// is the gyro's misalignment. (Its candidate was dropped once for a false flag on the plain clean flight, 5.5σ; that
/// flight's filter then held a t_d pulled by the vibrating gyro, docs/robustness.md "Weak excitation".)
constexpr int kLinCols = kGyroMis0 + 3 - kGyroAxY;
static_assert(kGyroAxZ == kGyroAxY + 1 && kExtRot0 == kGyroAxY + 2 && kGyroMis0 == kExtRot0 + 3, "column order");
Eigen::Matrix<double, 3, kLinCols> gyro_linear_cols(const Eigen::Vector3d &w) {
  Eigen::Matrix<double, 3, kLinCols> L = Eigen::Matrix<double, 3, kLinCols>::Zero();
  L(1, 0) = -w.y();
  L(2, 1) = -w.z();
  for (int j = 0; j < 3; ++j)
    L.col(2 + j) = w.cross(Eigen::Vector3d::Unit(j));
  const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (int p = 0; p < 3; ++p) {
    const int i = pairs[p][0], j = pairs[p][1];
    L(i, 5 + p) = -w(j);
    L(j, 5 + p) = -w(i);
  }
  return L;
}

/// The rate rows' clusters [s] and the Newey-West lags over them. An image's rates come from its features' slopes over
/// up to five images, so neighbouring images' errors correlate: measured on a clean agile 20-s log, the rows'
/// autocorrelation is 0.4-0.5 one image apart, 0.1-0.2 at two and three, within ±0.05 (its noise) from four images
/// on, and so are the scores of the time, readout and focal columns. Quarter seconds with two lags cover 15 images.
/// (One cluster per second, as before, covered 20 but left 20 clusters on 20 s, too few for the covariance.)
constexpr double kRateClusterS = 0.25;
constexpr int kRateHacLags = 2;

/// The rows of the design from the images' rates: the gyro bias per 5-s bin and axis (weighted means) removed from
/// the mismatch and the regressors of the ω rows (Frisch-Waugh). The ψ rows carry no gyro bias: α is a difference.
void fill_rate_rows(const std::vector<FrameRate> &fr, const DiagnoseReport &rep, Design &dr) {
  const int nb = std::max(1, static_cast<int>(std::lround(rep.duration_s / 5.0)));
  const auto bin = [&](double t) {
    return std::min(nb - 1, static_cast<int>(nb * t / std::max(1e-9, rep.duration_s)));
  };
  const double t_mid = 0.5 * rep.duration_s;
  std::vector<Eigen::Vector3d> sw(nb, Eigen::Vector3d::Zero()), sa(nb, Eigen::Vector3d::Zero()),
      sat(nb, Eigen::Vector3d::Zero()), sf(nb, Eigen::Vector3d::Zero()), ses(nb, Eigen::Vector3d::Zero()),
      sgs(nb, Eigen::Vector3d::Zero()), sar(nb, Eigen::Vector3d::Zero());
  // Weighted sums of the linear gyro columns and of α per offset bin, per bias bin (their part the bias takes).
  std::vector<Eigen::Matrix<double, 3, kLinCols>> slin(nb, Eigen::Matrix<double, 3, kLinCols>::Zero());
  std::vector<Eigen::Matrix<double, 3, kTdBins>> salpha_bin(nb, Eigen::Matrix<double, 3, kTdBins>::Zero());
  for (const auto &f : fr) {
    const Eigen::Vector3d w = f.se.cwiseInverse().cwiseAbs2();
    const int b = bin(f.t);
    sw[b] += w, sa[b] += w.cwiseProduct(f.alpha);
    sat[b] += w.cwiseProduct(f.alpha) * (f.t - t_mid);
    sf[b] += w.cwiseProduct(f.focal_e);
    sar[b] += w.cwiseProduct(f.alpha_row);
    ses[b] += w.cwiseProduct(f.e_s);
    sgs[b] += w.cwiseProduct(f.gyro_s);
    slin[b] += w.asDiagonal() * gyro_linear_cols(f.gyro_s);
    salpha_bin[b].col(td_bin(f.t, rep.duration_s)) += w.cwiseProduct(f.alpha);
  }
  const Eigen::Index n = kRateRowsPerImage * static_cast<Eigen::Index>(fr.size());
  dr.D = MatrixXd::Zero(n, kNumCols);
  dr.r.resize(n);
  dr.cluster.resize(n);
  dr.t_s.resize(n);
  dr.t_mid = t_mid;
  dr.have_velocity = true;
  dr.have_rate = false; // the residual's need for logged body rates does not apply here
  Eigen::Index i = 0;
  for (const auto &f : fr) {
    const int b = bin(f.t);
    // ω rows, ω_vis − ω̄_gyro: the time, focal and gyro columns on the same rows, so that the stepwise selection
    // weighs them against each other (an offset error otherwise read as a camera-body rotation on rows of its own).
    for (int a = 0; a < 3; ++a, ++i) {
      const double sq = 1.0 / f.se(a);
      dr.r(i) = sq * (f.e_s(a) - ses[b](a) / sw[b](a));
      dr.D(i, kV) = sq * (f.alpha(a) - sa[b](a) / sw[b](a));
      dr.D(i, kVt) = sq * (f.alpha(a) * (f.t - t_mid) - sat[b](a) / sw[b](a));
      for (int tb = 1; tb < kTdBins - 1; ++tb)
        dr.D(i, kTdBin0 + tb - 1) =
            sq * ((td_bin(f.t, rep.duration_s) == tb ? f.alpha(a) : 0.0) - salpha_bin[b](a, tb) / sw[b](a));
      dr.D(i, kVrow) = sq * (f.alpha_row(a) - sar[b](a) / sw[b](a));
      dr.D(i, kFocal) = sq * (f.focal_e(a) - sf[b](a) / sw[b](a));
      dr.D(i, kGyroScale) = -sq * (f.gyro_s(a) - sgs[b](a) / sw[b](a));
      const Eigen::Matrix<double, 3, kLinCols> L = gyro_linear_cols(f.gyro_s) - slin[b] / sw[b](a);
      for (int c = 0; c < kLinCols; ++c)
        dr.D(i, kGyroAxY + c) = sq * L(a, c);
    }
    for (int a = 0; a < 3; ++a, ++i) { // ψ rows
      const double sq = 1.0 / f.psi_se(a);
      dr.r(i) = sq * f.psi(a);
      dr.D(i, kVrow) = sq * f.alpha(a);
    }
    for (Eigen::Index q = i - kRateRowsPerImage; q < i; ++q) {
      dr.cluster[q] = static_cast<int>(f.t / kRateClusterS);
      dr.t_s[q] = f.t;
    }
  }
  dr.n_clusters = static_cast<int>(fr.back().t / kRateClusterS) + 1;
  dr.hac_lags = kRateHacLags;
  // The time bins reach an eighth of the log each (~7 independent clusters on 30 s): their variance takes the ratio
  // of the whole log's offset column (regression.h, Design::pooled_cols; docs/diagnose.md "Pooled variance").
  dr.pooled_cols = {kV, kVt};
  for (int tb = 0; tb < kTdBins - 2; ++tb)
    dr.pooled_cols.push_back(kTdBin0 + tb), dr.pooled_short.push_back(kTdBin0 + tb);
  std::vector<double> absr(n);
  for (Eigen::Index q = 0; q < n; ++q)
    absr[q] = std::abs(dr.r(q));
  dr.scale = std::max(1e-12, 1.4826 * median(absr));
}

/// The focal column's coefficient alone on the ω rows (whitened, bias bins taken out): where a focal error shows.
double focal_alone(const Design &dr) {
  const double num = dr.D.col(kFocal).dot(dr.r), den = dr.D.col(kFocal).squaredNorm();
  return den > 0 ? num / den : 0.0;
}

} // namespace

bool build_rate_design(const UsedData &data, const DiagnoseOptions &opt, const DiagnoseReport &rep, Design &dr,
                       std::string &why) {
  const FlowData flow = collect_flow(data.tracks, rep);
  const Eigen::Matrix3d R_BC_nominal = opt.camera.T_BC.block<3, 3>(0, 0);
  const ovton::core::CameraModel cam(opt.camera);
  // The filter's calibration at each image, when the log has one (filter_calibration.h): the IMU through its
  // intrinsics, its camera-body rotation, its readout time and focal.
  const std::vector<ovton::core::ImuData> imu_cal =
      opt.calibration.empty() ? std::vector<ovton::core::ImuData>{} : imu_through_calibration(opt.imu, opt.calibration);
  const std::vector<ovton::core::ImuData> &imu = opt.calibration.empty() ? opt.imu : imu_cal;
  const auto R_BC_at = [&](int64_t t_cam) {
    const CalibrationLogRow *cal = calibration_at(opt.calibration, t_cam);
    return cal ? mat3(cal->R_BC) : R_BC_nominal;
  };
  FlowFitter fitter(flow.n_tracks);
  FitMap fits, fits_psi;
  fitter.solve(flow.frames, fits, fits_psi);
  // ω̄_gyro (camera frame) with the fits and depth corrections of the data, then its response to a focal error.
  GyroThroughImages gyro_bar(imu);
  const auto omega_bar = [&](int64_t t_cam, const FrameFit &ff) {
    return gyro_bar.omega(flow.frames.at(t_cam), ff, fitter, R_BC_at(t_cam));
  };
  std::map<int64_t, Eigen::Vector3d> omega_bar0;
  for (const auto &[t_cam, ff] : fits)
    omega_bar0[t_cam] = omega_bar(t_cam, ff);
  const GyroSlope gyro_slope(imu);
  const double interval_ns = image_interval_ns(flow.frames);
  const auto frame_rates = [&] {
    std::vector<FrameRate> fr;
    for (const auto &[t_cam, ff] : fits) {
      const CalibrationLogRow *cal = calibration_at(opt.calibration, t_cam);
      const Eigen::Matrix3d R_BC = cal ? mat3(cal->R_BC) : R_BC_nominal;
      const auto body_se = [&](const Eigen::Matrix3d &C) {
        return (R_BC * C * R_BC.transpose()).diagonal().cwiseMax(1e-20).cwiseSqrt().eval();
      };
      FrameRate f;
      f.t = 1e-9 * double(t_cam - data.t_first);
      f.gyro_s = R_BC * omega_bar0.at(t_cam);
      f.focal_e = R_BC * ff.focal.head<3>();
      // What the filter's focal estimate already takes of the focal column.
      f.e_s = R_BC * ff.sol.head<3>() - f.gyro_s - (cal ? focal_estimate(*cal, rep.fu, rep.fv) : 0.0) * f.focal_e;
      f.alpha = gyro_slope.alpha(flow.frames.at(t_cam), interval_ns);
      f.alpha_row = R_BC * ff.psi_resp * R_BC.transpose() * f.alpha;
      if (cal) // what the filter's readout time already takes
        f.e_s -= cal->readout_s * f.alpha_row;
      f.se = body_se(ff.C.topLeftCorner<3, 3>());
      const auto fp = fits_psi.find(t_cam);
      if (fp != fits_psi.end()) { // ψ beyond the filter's readout time: ψ_vis − α·t̂_r
        f.psi = R_BC * fp->second.sol.segment<3>(3) - (cal ? cal->readout_s : 0.0) * f.alpha;
        f.psi_se = body_se(fp->second.C.block<3, 3>(3, 3));
      } else { // no ψ row: zero weight
        f.psi.setZero();
        f.psi_se.setConstant(1e30);
      }
      fr.push_back(f);
    }
    return fr;
  };
  // The focal response is not linear in the error (docs/diagnose.md, "What the focal reading is made of"): first a 1 %
  // step, then, where the rows show a focal error ε̂ of 0.2 % or more, the secant from the data back to no error
  // (a step of −ε̂), twice.
  const FlowFitter data_fit = fitter; // the data's depth corrections: add_focal_response leaves the perturbed ones
  add_focal_response(flow.frames, cam, fitter, fits, fits_psi, omega_bar, omega_bar0, 0.01);
  std::vector<FrameRate> fr = frame_rates();
  if (fr.size() < 50) {
    why = "only " + std::to_string(fr.size()) + " images with 12+ features of known depth";
    return false;
  }
  fill_rate_rows(fr, rep, dr);
  for (int it = 0; it < 2; ++it) {
    const double eps = focal_alone(dr);
    if (!(std::abs(eps) >= 0.002))
      break;
    fitter = data_fit;
    add_focal_response(flow.frames, cam, fitter, fits, fits_psi, omega_bar, omega_bar0, -eps);
    fr = frame_rates();
    fill_rate_rows(fr, rep, dr);
  }
  return true;
}

} // namespace ovton::eval::diag
