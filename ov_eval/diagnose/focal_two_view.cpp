#include "ov_eval/diagnose/focal_two_view.h"
#include "ov_core/cam/camera_model.h"
#include "ov_eval/diagnose/filter_calibration.h"
#include "ov_eval/diagnose/image_geometry.h"
#include "ov_eval/diagnose/regression.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>

namespace ovton::eval::diag {

namespace {

/// One pair of consecutive observations of a track.
struct Pair {
  Eigen::Vector2d x0, x1; ///< measured undistorted normalised points
  Eigen::Vector2d s0;     ///< the first's shift per unit relative focal error
  double rho0 = 0;        ///< the filter's inverse depth at the first
  int track = 0, frames = 0;
};

/// Per image pair: the camera's rotation R_{C0 C1} from the gyro.
struct FramePair {
  Eigen::Matrix3d R;
};

class Profile {
public:
  Profile(const ovton::core::CameraModel &cam, std::vector<Pair> pairs, std::vector<FramePair> frames, int n_tracks)
      : cam_(cam), p_(std::move(pairs)), f_(std::move(frames)), n_tracks_(n_tracks) {}

  /// The weighted cost with depths and translations fitted at ε; the residuals and weights stay in e_, w_.
  double cost(double eps) {
    const size_t n = p_.size();
    q_.resize(n), s1_.resize(n);
    for (size_t i = 0; i < n; ++i) { // the first point moved back to where the camera saw it, rotated into the second
      q_[i] = f_[p_[i].frames].R.transpose() * (p_[i].x0 - eps * p_[i].s0).homogeneous();
      s1_[i] = focal_dir(&cam_, q_[i].head<2>() / q_[i].z()); // at the rotation's prediction: see residuals()
    }
    rho_.assign(n_tracks_, 1.0);
    u_.assign(f_.size(), Eigen::Vector3d::Zero());
    w_.assign(n, 1.0);
    e_.resize(n);
    for (int it = 0; it < kIterations; ++it) {
      // Translations: e ≈ e0 − J_u·δu per image pair.
      residuals(eps);
      std::vector<Eigen::Matrix3d> N(f_.size(), Eigen::Matrix3d::Zero());
      std::vector<Eigen::Vector3d> b(f_.size(), Eigen::Vector3d::Zero());
      for (size_t i = 0; i < n; ++i) {
        Eigen::Matrix<double, 2, 3> J;
        J << -r_[i] / d_[i], 0, r_[i] * xp_[i].x() / d_[i], 0, -r_[i] / d_[i], r_[i] * xp_[i].y() / d_[i];
        N[p_[i].frames] += w_[i] * J.transpose() * J;
        b[p_[i].frames] += w_[i] * J.transpose() * e_[i];
      }
      for (size_t k = 0; k < f_.size(); ++k)
        if (N[k].determinant() > 1e-30)
          u_[k] += N[k].ldlt().solve(b[k]);
      // Per-track depth factors: e ≈ e0 − J_ρ·δρ.
      residuals(eps);
      std::vector<double> num(n_tracks_, 0.0), den(n_tracks_, 0.0);
      for (size_t i = 0; i < n; ++i) {
        const Eigen::Vector3d &u = u_[p_[i].frames];
        const Eigen::Vector2d J = p_[i].rho0 * (-u.head<2>() + xp_[i] * u.z()) / d_[i];
        num[p_[i].track] += w_[i] * J.dot(e_[i]);
        den[p_[i].track] += w_[i] * J.squaredNorm();
      }
      for (int t = 0; t < n_tracks_; ++t)
        rho_[t] += den[t] > 0 ? num[t] / den[t] : 0.0;
      residuals(eps);
      std::vector<double> en(n);
      for (size_t i = 0; i < n; ++i)
        en[i] = e_[i].norm();
      const double sc = std::max(1e-15, 1.4826 * median(en)); // Huber on the pair's residual, threshold 3σ
      for (size_t i = 0; i < n; ++i) {
        w_[i] = en[i] <= 3 * sc ? 1.0 : 3 * sc / en[i];
        s1_[i] = focal_dir(&cam_, xp_[i]); // the focal shift at the round's prediction (see residuals())
      }
    }
    residuals(eps);
    double c = 0;
    for (size_t i = 0; i < n; ++i)
      c += w_[i] * e_[i].squaredNorm();
    return c;
  }

  const std::vector<Eigen::Vector2d> &residual() const { return e_; }
  const std::vector<double> &weight() const { return w_; }
  const std::vector<Pair> &pairs() const { return p_; }

private:
  static constexpr int kIterations = 10; // the noise-free flight's residual: 0.025 px after 3, 0.018 after 10

  /// The second observation predicted from the point at ρ = ρ_track·ρ0 moved by the pair's translation u (in the
  /// second camera's frame): x' = (q_xy − ρ·u_xy)/(q_z − ρ·u_z), and its residual in measured coordinates: the
  /// prediction moved by ε·s(x'), s updated once a round (first at the rotation's prediction q_xy/q_z; left there,
  /// ε̂ read 5-9 % lower on the sizing logs and 0.84 % for 1 % noise-free). At the measured second point instead s
  /// shares that point's noise with the residual, and the profile then falls without a minimum (ε̂ beyond +10 %).
  void residuals(double eps) {
    const size_t n = p_.size();
    r_.resize(n), d_.resize(n), xp_.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d &u = u_[p_[i].frames];
      r_[i] = rho_[p_[i].track] * p_[i].rho0;
      d_[i] = q_[i].z() - r_[i] * u.z();
      xp_[i] = (q_[i].head<2>() - r_[i] * u.head<2>()) / d_[i];
      e_[i] = p_[i].x1 - (xp_[i] + eps * s1_[i]);
    }
  }

  const ovton::core::CameraModel &cam_;
  std::vector<Pair> p_;
  std::vector<FramePair> f_;
  int n_tracks_;
  std::vector<Eigen::Vector3d> q_, u_;
  std::vector<double> rho_, w_, r_, d_;
  std::vector<Eigen::Vector2d> xp_, e_, s1_;
};

} // namespace

TwoViewFocal focal_two_view(const UsedData &data, const DiagnoseOptions &opt, double centre) {
  TwoViewFocal out;
  if (!opt.have_camera || opt.imu.empty()) {
    out.why = "needs --dataset (the camera and the raw gyro)";
    return out;
  }
  const ovton::core::CameraModel cam(opt.camera);
  const std::vector<ovton::core::ImuData> imu = imu_through_calibration(opt.imu, opt.calibration);
  std::vector<Pair> pairs;
  std::vector<FramePair> frames;
  std::map<std::pair<int64_t, int64_t>, int> frame_index;
  int n_tracks = 0;
  for (const auto &kv : data.tracks) {
    Track tr = kv.second;
    std::sort(tr.begin(), tr.end(), [](const auto *a, const auto *b) { return a->t_cam_ns < b->t_cam_ns; });
    bool used = false;
    for (size_t k = 0; k + 1 < tr.size(); ++k) {
      const ResidualLogRow &a = *tr[k], &b = *tr[k + 1];
      if (!(std::isfinite(a.depth_m) && a.depth_m > 0) || b.t_cam_ns - a.t_cam_ns > 150'000'000)
        continue;
      const auto key = std::make_pair(a.t_cam_ns, b.t_cam_ns);
      auto it = frame_index.find(key);
      if (it == frame_index.end()) {
        const CalibrationLogRow *c = calibration_at(opt.calibration, a.t_cam_ns);
        const Eigen::Matrix3d R_BC = c ? mat3(c->R_BC) : Eigen::Matrix3d(opt.camera.T_BC.block<3, 3>(0, 0));
        const Eigen::Vector3d bg = c ? Eigen::Vector3d(c->b_g[0], c->b_g[1], c->b_g[2]) : Eigen::Vector3d::Zero();
        const Eigen::Matrix3d D_w = c ? mat3(c->D_w) : Eigen::Matrix3d::Identity();
        // imu is already through D_w: the filter's ω = D_w·(ω_m − b_g), so the bias goes through it too.
        const Eigen::Matrix3d R_B =
            body_rotation(imu, double(a.t_cam_ns) + 1e9 * a.td_s, double(b.t_cam_ns) + 1e9 * b.td_s, D_w * bg);
        frames.push_back({R_BC.transpose() * R_B * R_BC});
        it = frame_index.emplace(key, static_cast<int>(frames.size()) - 1).first;
      }
      Pair p;
      p.x0 = Eigen::Vector2d(a.x_norm, a.y_norm);
      p.x1 = Eigen::Vector2d(b.x_norm, b.y_norm);
      p.s0 = focal_dir(&cam, p.x0);
      p.rho0 = 1.0 / a.depth_m;
      p.track = n_tracks;
      p.frames = it->second;
      pairs.push_back(p);
      used = true;
    }
    n_tracks += used;
  }
  out.pairs = static_cast<long>(pairs.size());
  if (pairs.size() < 200) {
    out.why = "fewer than 200 pairs of consecutive observations with a depth";
    return out;
  }
  Profile prof(cam, std::move(pairs), std::move(frames), n_tracks);
  // The profile on a grid of 0.5 % around the rates' estimate, then a parabola through the lowest point and its
  // neighbours (the profile is smooth: docs/diagnose.md).
  const double step = 0.005;
  std::vector<double> grid, cost;
  for (int g = -4; g <= 4; ++g) {
    grid.push_back(centre + g * step);
    cost.push_back(prof.cost(grid.back()));
  }
  const size_t i = std::clamp<size_t>(std::min_element(cost.begin(), cost.end()) - cost.begin(), 1, grid.size() - 2);
  const double a = cost[i - 1], b = cost[i], c = cost[i + 1], curv = a - 2 * b + c;
  if (!(curv > 0)) {
    out.why = "the profile has no minimum within 2 % of the rates' estimate";
    return out;
  }
  out.eps = grid[i] + 0.5 * step * (a - c) / curv;
  // σ: the profile's derivative of every residual (central difference, nuisance refitted) and the scores summed per
  // track (a track's pairs share its points' noise and its depth).
  const double h = 1e-3;
  prof.cost(out.eps + h);
  const std::vector<Eigen::Vector2d> e_plus = prof.residual();
  prof.cost(out.eps - h);
  const std::vector<Eigen::Vector2d> e_minus = prof.residual();
  prof.cost(out.eps);
  std::vector<double> score(n_tracks, 0.0);
  double info = 0;
  for (size_t k = 0; k < prof.pairs().size(); ++k) {
    const Eigen::Vector2d g = (e_plus[k] - e_minus[k]) / (2 * h);
    info += prof.weight()[k] * g.squaredNorm();
    score[prof.pairs()[k].track] += prof.weight()[k] * g.dot(prof.residual()[k]);
  }
  double meat = 0;
  for (double s : score)
    meat += s * s;
  out.se = info > 0 ? std::sqrt(meat) / info : 0.0;
  out.ok = true;
  return out;
}

void size_focal_from_two_views(const UsedData &data, const DiagnoseOptions &opt, const DiagnoseReport &rep,
                               CandidateResult &focal) {
  const auto rel = std::find_if(focal.estimates.begin(), focal.estimates.end(),
                                [](const EffectEstimate &e) { return e.name == "relative focal error ε"; });
  if (rel == focal.estimates.end())
    return;
  const TwoViewFocal tv = focal_two_view(data, opt, 1e-2 * rel->value);
  const auto add_note = [&](const std::string &n) { focal.note += (focal.note.empty() ? "" : "; ") + n; };
  if (!tv.ok) {
    add_note("sized by the rates' column (two views: " + tv.why + ")");
    return;
  }
  const double f = 0.5 * (rep.fu + rep.fv);
  EffectEstimate rates = *rel;
  rates.name = "relative focal error ε (rates)";
  focal.estimates = {{"focal error δf", "px", f * tv.eps, f * tv.se},
                     {"relative focal error ε", "%", 100 * tv.eps, 100 * tv.se},
                     rates};
  add_note("sized from two views and the gyro (" + std::to_string(tv.pairs) + " pairs)");
}

} // namespace ovton::eval::diag
