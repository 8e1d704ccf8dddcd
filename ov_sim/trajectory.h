#pragma once
// Smooth SE(3) trajectories for the simulator: analytic derivatives so the synthetic IMU is exact.
#include "ov_core/types/sensor_data.h"
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <vector>

namespace ovton::sim {

/// Body (IMU) state at one instant. Derivatives are exact derivatives of the pose, not finite differences.
struct TrajectorySample {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity(); ///< Hamilton, body -> world
  Eigen::Vector3d v_W = Eigen::Vector3d::Zero();            ///< dp/dt in world
  Eigen::Vector3d a_W = Eigen::Vector3d::Zero();            ///< d2p/dt2 in world (no gravity)
  Eigen::Vector3d w_B = Eigen::Vector3d::Zero();            ///< angular velocity in body: dR/dt = R [w_B]x
};

class Trajectory {
public:
  virtual ~Trajectory() = default;
  /// Valid time span, IMU clock [ns].
  virtual int64_t t_begin_ns() const = 0;
  virtual int64_t t_end_ns() const = 0;
  /// Evaluated at IMU-clock time t_ns (clamped to the valid span).
  virtual TrajectorySample sample(int64_t t_ns) const = 0;
  /// Human-readable origin, recorded in sim.yaml.
  virtual std::string describe() const = 0;
};

/// Uniform cubic B-spline (C2) fitted by regularised least squares through a ground-truth trajectory.
/// Position: spline in R^3. Orientation: spline of the (sign-continuous) quaternion components,
/// renormalised, which is C2 wherever the spline stays away from zero (it stays near unit norm).
class SplineTrajectory : public Trajectory {
public:
  /// Fits over [t_begin_ns, t_end_ns] (clamped to the samples' span). Samples outside [t_begin - 1 s,
  /// t_end + 1 s] are ignored. knot_dt_s sets the smoothing: 0.1 s keeps EuRoC's motion and drops mocap jitter.
  SplineTrajectory(const std::vector<ovton::core::StateSample> &gt, int64_t t_begin_ns, int64_t t_end_ns,
                   double knot_dt_s = 0.1, const std::string &source = "");

  int64_t t_begin_ns() const override { return t_begin_ns_; }
  int64_t t_end_ns() const override { return t_end_ns_; }
  TrajectorySample sample(int64_t t_ns) const override;
  std::string describe() const override { return source_; }
  double knot_dt_s() const { return dt_; }

private:
  int64_t t_begin_ns_, t_end_ns_;
  int64_t t0_ns_; ///< time of the first segment's start
  double dt_;
  std::vector<Eigen::Vector3d> cp_pos_;
  std::vector<Eigen::Vector4d> cp_quat_; ///< (w, x, y, z)
  std::string source_;
};

/// Built-in flight through a 6 x 6 x 3 m room centred on (0, 0, 1.5): a Lissajous curve in position,
/// yaw sweeping with smooth roll/pitch wobble; camera (EuRoC body z) looks mostly horizontally. Its angular
/// accelerations are gentle (≈ 0.15 rad/s²); `agility` > 0 adds faster roll/pitch/yaw oscillations with angular
/// accelerations of ≈ agility × (0.8–1.6) rad/s², as in EuRoC's medium sequences (what a rolling shutter needs to
/// show).
class LissajousTrajectory : public Trajectory {
public:
  static constexpr int64_t kDefaultBeginNs = 1600000000000000000LL;
  explicit LissajousTrajectory(double duration_s = 60.0, int64_t t_begin_ns = kDefaultBeginNs, double agility = 0.0);
  int64_t t_begin_ns() const override { return t_begin_ns_; }
  int64_t t_end_ns() const override { return t_begin_ns_ + ovton::core::s_to_ns(duration_s_); }
  TrajectorySample sample(int64_t t_ns) const override;
  std::string describe() const override;

private:
  int64_t t_begin_ns_;
  double duration_s_;
  double agility_;
};

/// Ground-truth sample of the trajectory (no biases) at t_ns.
ovton::core::StateSample to_state_sample(const TrajectorySample &s, int64_t t_ns);

} // namespace ovton::sim
