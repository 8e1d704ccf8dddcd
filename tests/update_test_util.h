#pragma once
// Synthetic MSCKF scenes for the update tests: a smooth body trajectory, points seen by every clone, a state whose
// clones sit at the truth, noisy observations.
#include "fd_check.h"
#include "ov_core/cam/camera_model.h"
#include "ov_core/math/so3.h"
#include "ov_core/track/feature_database.h"
#include "ov_msckf_ton/state/state.h"
#include "ov_msckf_ton/update/feature_jacobians.h"
#include "ov_msckf_ton/update/updater_msckf.h"
#include "ov_sim/euroc_calib.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <utility>
#include <vector>

namespace updtest {

using namespace ovton::msckf;
using ovton::core::so3_exp;
using ovton::core::so3_log;

/// EuRoC cam0 with the rotation of its T_BS re-orthonormalised: the Jacobians take R_BC⁻¹ = R_BCᵀ, and the
/// finite-difference checks below compare at 1e-7.
inline ovton::core::CameraCalib euroc_cam0() {
  ovton::core::CameraCalib c = ovton::sim::euroc_cam0_calib();
  const Eigen::Quaterniond q(Eigen::Matrix3d(c.T_BC.topLeftCorner<3, 3>()));
  c.T_BC.topLeftCorner<3, 3>() = q.normalized().toRotationMatrix();
  return c;
}

/// EuRoC cam1, its rotation re-orthonormalised as euroc_cam0's.
inline ovton::core::CameraCalib euroc_cam1() {
  ovton::core::CameraCalib c = ovton::sim::euroc_cam1_calib();
  const Eigen::Quaterniond q(Eigen::Matrix3d(c.T_BC.topLeftCorner<3, 3>()));
  c.T_BC.topLeftCorner<3, 3>() = q.normalized().toRotationMatrix();
  return c;
}

struct Pose {
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
};

/// A smooth body trajectory with non-constant angular and linear velocity (so that a time shift is not a rigid
/// transform of the window, which would make t_d unobservable). `rate` scales the motion.
inline Pose body_pose(double t, double rate) {
  const Eigen::Vector3d th(0.25 * std::sin(rate * 1.3 * t), 0.3 * std::sin(rate * 0.9 * t + 0.5),
                           0.2 * std::sin(rate * 1.7 * t + 1.0));
  Pose P;
  P.R = so3_exp(th);
  P.p = Eigen::Vector3d(0.5 * std::sin(rate * 0.8 * t), 0.3 * std::sin(rate * 1.1 * t + 0.3),
                        0.2 * std::sin(rate * 0.7 * t));
  return P;
}

constexpr int64_t kT0 = 1403636579763555584; // a EuRoC-sized stamp: differences must stay exact in int64

struct Scene {
  ovton::core::CameraCalib calib = euroc_cam0();
  ovton::core::CameraModel cam{calib};
  Eigen::Matrix3d R_BC = calib.T_BC.topLeftCorner<3, 3>();
  Eigen::Vector3d p_BC = calib.T_BC.topRightCorner<3, 1>();
  double rate = 1.0;
  double td_true = 0.0; ///< observations are taken at IMU time t_cam + td_true
  std::vector<int64_t> stamps;
  std::vector<Eigen::Vector3d> points;

  double t_of(int64_t t_cam_ns) const { return static_cast<double>(t_cam_ns - kT0) * 1e-9; }
  Pose pose_at(double t_imu) const { return body_pose(t_imu, rate); }
  /// Undistorted normalised projection of a world point by the body pose at IMU time t.
  bool project(const Pose &P, const Eigen::Vector3d &p_W, Eigen::Vector2d &xy) const {
    return project_in_clone(P.R, P.p, R_BC, p_BC, p_W, xy, nullptr, nullptr, 0.2);
  }
  bool visible(const Pose &P, const Eigen::Vector3d &p_W) const {
    Eigen::Vector2d xy;
    return project(P, p_W, xy) && cam.in_image(cam.distort(xy), 10.0);
  }
};

/// n_clones images at 20 Hz and points at 3–6 m seen by every one of them (at truth, with td_true).
inline Scene make_scene(int n_clones, int n_points, double rate, double td_true, unsigned seed) {
  Scene sc;
  sc.rate = rate;
  sc.td_true = td_true;
  for (int k = 0; k < n_clones; ++k)
    sc.stamps.push_back(kT0 + static_cast<int64_t>(k) * 50'000'000);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-0.5, 0.5), ud(3.0, 6.0);
  const Pose P0 = sc.pose_at(sc.t_of(sc.stamps[n_clones / 2]) + td_true);
  int tries = 0;
  while (static_cast<int>(sc.points.size()) < n_points && ++tries < 100000) {
    const double d = ud(rng);
    const Eigen::Vector3d p_C(ux(rng) * d, 0.6 * ux(rng) * d, d);
    const Eigen::Vector3d p_W = P0.R * (sc.R_BC * p_C + sc.p_BC) + P0.p;
    bool all = true;
    for (int64_t t : sc.stamps)
      all = all && sc.visible(sc.pose_at(sc.t_of(t) + td_true), p_W);
    if (all)
      sc.points.push_back(p_W);
  }
  return sc;
}

/// A state whose clones sit at the truth pose of IMU time t_cam + td_ref, with independent priors per clone.
inline State make_state(const Scene &sc, double td_ref, double sig_th, double sig_p, double sig_td) {
  State s(true);
  const int n = ImuState::kSize + 1 + CloneState::kSize * static_cast<int>(sc.stamps.size());
  s.P = Eigen::MatrixXd::Zero(n, n);
  s.P.topLeftCorner<15, 15>() = 1e-4 * Eigen::Matrix<double, 15, 15>::Identity();
  s.td = td_ref;
  s.P(s.td_index, s.td_index) = sig_td * sig_td;
  int idx = ImuState::kSize + 1;
  for (int64_t t : sc.stamps) {
    CloneState c;
    c.t_cam_ns = t;
    c.td_ref = td_ref;
    c.t_imu_ns = t + static_cast<int64_t>(std::llround(td_ref * 1e9));
    const Pose P = sc.pose_at(sc.t_of(t) + td_ref);
    c.R = P.R;
    c.p = P.p;
    c.index = idx;
    for (int j = 0; j < 3; ++j) {
      s.P(idx + j, idx + j) = sig_th * sig_th;
      s.P(idx + 3 + j, idx + 3 + j) = sig_p * sig_p;
    }
    idx += CloneState::kSize;
    s.clones[t] = c;
  }
  return s;
}

/// A filter's clones share most of their error (they descend from one propagated state): adds an error common to all
/// clones, sig_th_common [rad] and sig_p_common [m] per axis, to a state's prior (make_state's are independent).
inline void add_common_clone_prior(State &s, double sig_th_common, double sig_p_common) {
  for (const auto &[ta, a] : s.clones)
    for (const auto &[tb, b] : s.clones)
      for (int q = 0; q < 3; ++q) {
        s.P(a.index + q, b.index + q) += sig_th_common * sig_th_common;
        s.P(a.index + 3 + q, b.index + 3 + q) += sig_p_common * sig_p_common;
      }
}

/// Observes every point in every image (at IMU time t_cam + td_true) with Gaussian pixel noise.
inline void observe(const Scene &sc, ovton::core::FeatureDatabase &db, double noise_px, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise_px);
  for (int64_t t : sc.stamps) {
    const Pose P = sc.pose_at(sc.t_of(t) + sc.td_true);
    for (size_t id = 0; id < sc.points.size(); ++id) {
      Eigen::Vector2d xy;
      ASSERT_TRUE(sc.project(P, sc.points[id], xy));
      const Eigen::Vector2d uv = sc.cam.distort(xy) + Eigen::Vector2d(n(rng), n(rng));
      db.add_observation(id, t, uv, sc.cam.undistort(uv));
    }
  }
}

/// As observe, with each point's pixel errors AR(1) over the images (e_k = ρ e_{k−1} + √(1 − ρ²) w_k, marginal σ
/// noise_px, u and v apart): KLT's tracks drift this way.
inline void observe_ar1(const Scene &sc, ovton::core::FeatureDatabase &db, double noise_px, double rho, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise_px);
  std::vector<Eigen::Vector2d> e(sc.points.size());
  for (auto &ei : e)
    ei = Eigen::Vector2d(n(rng), n(rng));
  const double s = std::sqrt(1.0 - rho * rho);
  bool first = true;
  for (int64_t t : sc.stamps) {
    const Pose P = sc.pose_at(sc.t_of(t) + sc.td_true);
    for (size_t id = 0; id < sc.points.size(); ++id) {
      if (!first)
        e[id] = rho * e[id] + s * Eigen::Vector2d(n(rng), n(rng));
      Eigen::Vector2d xy;
      ASSERT_TRUE(sc.project(P, sc.points[id], xy));
      const Eigen::Vector2d uv = sc.cam.distort(xy) + e[id];
      db.add_observation(id, t, uv, sc.cam.undistort(uv));
    }
    first = false;
  }
}

/// Camera 1's track of point `id` (EuRoC cam1, euroc_cam1()) in every image, seen at the poses `delta` seconds of
/// motion after cam0's (a camera whose images come `delta` after cam0's at the same stamp), Gaussian pixel noise of
/// noise_px from `rng`. Returns cam1's calibration.
inline ovton::core::CameraCalib add_cam1_track(const Scene &sc, ovton::core::FeatureDatabase &db, size_t id,
                                               double delta, double noise_px = 0.0, std::mt19937 *rng = nullptr) {
  const ovton::core::CameraCalib cal1 = euroc_cam1();
  const ovton::core::CameraModel cam1(cal1);
  std::normal_distribution<double> n(0.0, noise_px);
  for (int64_t t : sc.stamps) {
    const Pose P = sc.pose_at(sc.t_of(t) + sc.td_true + delta);
    Eigen::Vector2d xy;
    EXPECT_TRUE(project_in_clone(P.R, P.p, cal1.T_BC.topLeftCorner<3, 3>(), cal1.T_BC.topRightCorner<3, 1>(),
                                 sc.points[id], xy));
    Eigen::Vector2d uv = cam1.distort(xy);
    if (rng)
      uv += Eigen::Vector2d(n(*rng), n(*rng));
    db.add_observation(id, t, uv, cam1.undistort(uv), 1);
  }
  return cal1;
}

/// The further camera's Jacobian case: a state at the truth of make_scene(5, 5, 2.0, 0.0, 21) with t_d 4 ms and camera
/// 1's own Δ of 3 ms in it, every point seen by cam0 and point `id` by cam1 with its images 4 ms after cam0's.
struct Cam1Case {
  Scene sc = make_scene(5, 5, 2.0, 0.0, 21);
  State s = make_state(sc, 0.0, 0.01, 0.02, 0.02);
  ovton::core::FeatureDatabase db;
  ovton::core::CameraCalib cal1;
  size_t id = 3;

  Cam1Case() {
    EXPECT_EQ(sc.points.size(), 5u);
    s.td = 0.004;
    s.cam_td.push_back({0.003, s.add_variable(Eigen::MatrixXd::Constant(1, 1, 1e-4))});
    observe(sc, db, 0.0, 1);
    cal1 = add_cam1_track(sc, db, id, 0.004);
  }
};

inline std::vector<const ovton::core::Feature *> all_features(const ovton::core::FeatureDatabase &db) {
  std::vector<const ovton::core::Feature *> out;
  db.features_older_than(std::numeric_limits<int64_t>::max(), out);
  return out;
}

/// `lin` (columns each once: merge_repeated_columns for a rig) against central differences: r = z − h(x), so H =
/// −∂r/∂x, of the state ⊞-perturbed along lin.cols and of the feature position.
inline void expect_linearization_matches_fd(const UpdaterMSCKF &up, const State &s, const ovton::core::Feature &f,
                                            const Eigen::Vector3d &p_f, TdObservation td_obs,
                                            const VelocityProvider &vp, const FeatureLinearization &lin) {
  const auto minus_r = [&](const State &si, const Eigen::Vector3d &p_fi) -> Eigen::VectorXd {
    FeatureLinearization li;
    EXPECT_TRUE(up.linearize(si, f, p_fi, td_obs, vp, li));
    return -li.r;
  };
  const auto along_cols = [&](const State &si, const Eigen::VectorXd &d) {
    Eigen::VectorXd dx = Eigen::VectorXd::Zero(si.dim());
    for (size_t j = 0; j < lin.cols.size(); ++j)
      dx(lin.cols[j]) = d(static_cast<Eigen::Index>(j));
    State out = si;
    out.boxplus(dx);
    return out;
  };
  const double h = 1e-6;
  const Eigen::MatrixXd num_x = ovtest::numeric_jacobian([&](const State &si) { return minus_r(si, p_f); }, s,
                                                         static_cast<Eigen::Index>(lin.cols.size()), along_cols, h);
  for (size_t j = 0; j < lin.cols.size(); ++j)
    EXPECT_LT((num_x.col(j) - lin.H_x.col(j)).norm(), 1e-6 * (1 + lin.H_x.col(j).norm())) << "column " << j;
  const Eigen::MatrixXd num_f =
      ovtest::numeric_jacobian([&](const Eigen::Vector3d &p_fi) { return minus_r(s, p_fi); }, p_f, h);
  for (int i = 0; i < 3; ++i)
    EXPECT_LT((num_f.col(i) - lin.H_f.col(i)).norm(), 1e-6 * (1 + lin.H_f.col(i).norm())) << "feature axis " << i;
}

/// Rotation and position error of a clone against the truth pose of its IMU time.
inline std::pair<double, double> clone_error(const Scene &sc, const CloneState &c, double td) {
  const Pose P = sc.pose_at(sc.t_of(c.t_cam_ns) + td);
  return {so3_log(P.R.transpose() * c.R).norm(), (c.p - P.p).norm()};
}

} // namespace updtest
