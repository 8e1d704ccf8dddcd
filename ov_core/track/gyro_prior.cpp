#include "ov_core/track/gyro_prior.h"

#include <cmath>

namespace ovton::core {

GyroRotationPrior::GyroRotationPrior(std::shared_ptr<const ImuBuffer> imu, const Eigen::Matrix3d &R_IC, double td_s)
    : imu_(std::move(imu)), R_IC_(R_IC), td_ns_(static_cast<int64_t>(std::llround(td_s * 1e9))) {}

std::optional<Eigen::Matrix3d> GyroRotationPrior::camera_rotation(int64_t t0_cam_ns, int64_t t1_cam_ns) const {
  const auto R_I0_I1 = imu_->rotation(t0_cam_ns + td_ns_, t1_cam_ns + td_ns_);
  if (!R_I0_I1)
    return std::nullopt;
  // R_{C0 C1} = R_CI R_{I0 I1} R_IC; its transpose maps image 0's bearings into camera 1.
  return (R_IC_.transpose() * *R_I0_I1 * R_IC_).transpose();
}

} // namespace ovton::core
