#pragma once
// The camera's rotation between two images from the raw gyro: where KLT should start looking for each point.
// A rotation moves every point of the image far more than the translation between two frames does (a turn at
// 2 rad/s is 46 px per 50 ms image at EuRoC's focal length); starting LK where the rotation takes a point leaves only
// the parallax to the pyramid, so fewer levels find it.
#include "ov_core/types/imu_buffer.h"

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace ovton::core {

class GyroRotationPrior {
public:
  /// `imu`: the readings (IMU clock), which a streaming caller may keep appending to between queries; R_IC: camera
  /// -> IMU rotation; td_s: the offset t_imu = t_cam + t_d at which image stamps are looked up in the IMU log. The
  /// gyro's bias is not known here and not removed (EuRoC's ~0.02 rad/s moves a point by ~0.5 px per image, well
  /// inside LK's window).
  GyroRotationPrior(std::shared_ptr<const ImuBuffer> imu, const Eigen::Matrix3d &R_IC, double td_s);
  /// The same over a whole recording's log.
  GyroRotationPrior(const std::vector<ImuData> &imu, const Eigen::Matrix3d &R_IC, double td_s)
      : GyroRotationPrior(std::make_shared<const ImuBuffer>(imu), R_IC, td_s) {}

  /// R_{C1 C0}: takes a bearing of the image at t0 into the camera frame of the image at t1 (both camera clock).
  /// Empty when the IMU log does not cover [t0, t1] + t_d or t1 <= t0.
  std::optional<Eigen::Matrix3d> camera_rotation(int64_t t0_cam_ns, int64_t t1_cam_ns) const;
  /// The IMU-clock time up to which the readings must reach for camera_rotation(·, t_cam_ns).
  int64_t imu_time(int64_t t_cam_ns) const { return t_cam_ns + td_ns_; }

private:
  std::shared_ptr<const ImuBuffer> imu_;
  Eigen::Matrix3d R_IC_;
  int64_t td_ns_;
};

} // namespace ovton::core
