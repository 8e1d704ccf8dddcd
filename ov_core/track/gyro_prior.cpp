#include "ov_core/track/gyro_prior.h"
#include "ov_core/math/so3.h"

#include <algorithm>
#include <cmath>

namespace ovton::core {

GyroRotationPrior::GyroRotationPrior(const std::vector<ImuData> &imu, const Eigen::Matrix3d &R_IC, double td_s)
    : R_IC_(R_IC), td_ns_(static_cast<int64_t>(std::llround(td_s * 1e9))) {
  t_ns_.reserve(imu.size());
  w_.reserve(imu.size());
  for (const auto &m : imu) {
    t_ns_.push_back(m.t_imu_ns);
    w_.push_back(m.wm);
  }
}

std::optional<Eigen::Matrix3d> GyroRotationPrior::camera_rotation(int64_t t0_cam_ns, int64_t t1_cam_ns) const {
  const int64_t a = t0_cam_ns + td_ns_, b = t1_cam_ns + td_ns_;
  if (b <= a || t_ns_.size() < 2 || a < t_ns_.front() || b > t_ns_.back())
    return std::nullopt;
  // Readings k with t_k <= a < t_{k+1}: the rate is interpolated linearly between readings and each piece of
  // [a, b] between two readings rotates by its mean rate (trapezoid).
  size_t k = static_cast<size_t>(std::upper_bound(t_ns_.begin(), t_ns_.end(), a) - t_ns_.begin()) - 1;
  const auto rate_at = [&](size_t i, int64_t t) -> Eigen::Vector3d {
    const double span = static_cast<double>(t_ns_[i + 1] - t_ns_[i]);
    const double s = span > 0 ? static_cast<double>(t - t_ns_[i]) / span : 0.0;
    return (1.0 - s) * w_[i] + s * w_[i + 1];
  };
  Eigen::Matrix3d R_I0_I = Eigen::Matrix3d::Identity();
  int64_t t = a;
  while (t < b && k + 1 < t_ns_.size()) {
    const int64_t t_end = std::min(b, t_ns_[k + 1]);
    if (t_end > t) {
      const Eigen::Vector3d w = 0.5 * (rate_at(k, t) + rate_at(k, t_end));
      R_I0_I = R_I0_I * so3_exp(w * (static_cast<double>(t_end - t) * 1e-9));
    }
    t = t_end;
    ++k;
  }
  // R_{C0 C1} = R_CI R_{I0 I1} R_IC; its transpose maps image 0's bearings into camera 1.
  return (R_IC_.transpose() * R_I0_I * R_IC_).transpose();
}

} // namespace ovton::core
