#pragma once
// IMU synthesis from a trajectory: w_m = w_B + b_g + n_g,  a_m = R_WB^T (a_W - g_W) + b_a + n_a.
#include "ov_core/cam/camera_calib.h"
#include "ov_core/types/sensor_data.h"
#include "ov_sim/trajectory.h"
#include <vector>

namespace ovton::sim {

struct ImuSynthOptions {
  ovton::core::ImuCalib calib;                                  ///< rate and continuous-time noise densities
  Eigen::Vector3d gravity_W = Eigen::Vector3d(0.0, 0.0, -9.81); ///< world z up
  Eigen::Vector3d bg0 = Eigen::Vector3d::Zero();                ///< initial gyro bias [rad/s]
  Eigen::Vector3d ba0 = Eigen::Vector3d::Zero();                ///< initial accel bias [m/s^2]
  bool add_noise = true;                                        ///< white noise
  bool add_bias_walk = true;                                    ///< bias random walk
  double gyro_scale = 0.0; ///< planted scale error: the gyro reads (1 + gyro_scale)·ω (+ bias + noise)
  /// Planted per-axis scale and misalignment: the gyro reads (1 + gyro_scale)·(I + gyro_M)·ω, the accelerometer
  /// (I + accel_M)·f (f the specific force), before bias and noise. Zero: none.
  Eigen::Matrix3d gyro_M = Eigen::Matrix3d::Zero(), accel_M = Eigen::Matrix3d::Zero();
  uint64_t seed = 0;
};

struct ImuSynthResult {
  std::vector<ovton::core::ImuData> imu;
  std::vector<ovton::core::StateSample> truth; ///< true state (pose, velocity, biases) at every IMU stamp
};

/// Samples the IMU at calib.rate_hz on [traj.t_begin_ns(), traj.t_end_ns()], stamps on an exact ns grid.
/// Discrete white-noise sigma = density * sqrt(rate); bias step sigma = random_walk * sqrt(dt).
ImuSynthResult synthesize_imu(const Trajectory &traj, const ImuSynthOptions &opt);

/// Ideal (noise-free, bias-free) measurement at one instant.
ovton::core::ImuData ideal_imu(const TrajectorySample &s, int64_t t_ns, const Eigen::Vector3d &gravity_W);

} // namespace ovton::sim
