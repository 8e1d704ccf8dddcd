#pragma once
// Static initialisation: gravity direction and gyro bias from a still stretch of IMU data (every EuRoC sequence
// starts still on the ground).
#include "ov_core/types/sensor_data.h"

#include <deque>
#include <string>

namespace ovton::msckf {

struct StaticInitResult {
  bool ok = false;
  std::string why; ///< reason when !ok
  Eigen::Matrix3d R_WB = Eigen::Matrix3d::Identity();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();
  double accel_std = 0.0, gyro_std = 0.0;
};

/// Uses the readings in [t_end − window, t_end]. At rest a_m = R_WBᵀ(−g) + b_a, so the mean specific force is
/// the world z axis seen from the body; yaw is unobservable and set to zero (the body x axis projected on the
/// horizontal plane is world x). b_a cannot be told apart from tilt here and starts at zero.
StaticInitResult static_initialize(const std::deque<ovton::core::ImuData> &imu, int64_t t_end_ns, double window_s,
                                   double max_accel_std, double max_gyro_std);

} // namespace ovton::msckf
