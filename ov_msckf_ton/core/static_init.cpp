#include "ov_msckf_ton/core/static_init.h"

#include <cmath>

namespace ovton::msckf {

StaticInitResult static_initialize(const std::deque<ovton::core::ImuData> &imu, int64_t t_end_ns, double window_s,
                                   double max_accel_std, double max_gyro_std) {
  StaticInitResult r;
  const int64_t t_begin = t_end_ns - ovton::core::s_to_ns(window_s);
  if (imu.empty() || imu.front().t_imu_ns > t_begin) {
    r.why = "not enough IMU data yet";
    return r;
  }
  Eigen::Vector3d sa = Eigen::Vector3d::Zero(), sw = Eigen::Vector3d::Zero();
  int n = 0;
  for (const auto &m : imu)
    if (m.t_imu_ns >= t_begin && m.t_imu_ns <= t_end_ns) {
      sa += m.am;
      sw += m.wm;
      ++n;
    }
  if (n < 10) {
    r.why = "fewer than 10 IMU readings in the window";
    return r;
  }
  const Eigen::Vector3d a_mean = sa / n, w_mean = sw / n;
  double va = 0, vw = 0;
  for (const auto &m : imu)
    if (m.t_imu_ns >= t_begin && m.t_imu_ns <= t_end_ns) {
      va += (m.am - a_mean).squaredNorm();
      vw += (m.wm - w_mean).squaredNorm();
    }
  r.accel_std = std::sqrt(va / n);
  r.gyro_std = std::sqrt(vw / n);
  if (r.accel_std > max_accel_std || r.gyro_std > max_gyro_std) {
    r.why = "platform is moving (accel std " + std::to_string(r.accel_std) + " m/s^2, gyro std " +
            std::to_string(r.gyro_std) + " rad/s)";
    return r;
  }
  // Columns of R_WBᵀ are the world axes in body coordinates.
  const Eigen::Vector3d z = a_mean.normalized();
  Eigen::Vector3d x = Eigen::Vector3d::UnitX() - z * z.x();
  if (x.norm() < 0.1) // body x nearly vertical: use body y for the heading reference instead
    x = Eigen::Vector3d::UnitY() - z * z.y();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d Rt;
  Rt.col(0) = x;
  Rt.col(1) = y;
  Rt.col(2) = z;
  r.R_WB = Rt.transpose();
  r.bg = w_mean;
  r.ok = true;
  return r;
}

} // namespace ovton::msckf
