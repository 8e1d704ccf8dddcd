#include "ov_eval/diagnose/filter_calibration.h"

#include "ov_core/math/so3.h"

#include <algorithm>
#include <cmath>

namespace ovton::eval::diag {

const CalibrationLogRow *calibration_at(const std::vector<CalibrationLogRow> &rows, int64_t t_cam_ns) {
  if (rows.empty())
    return nullptr;
  const auto it = std::lower_bound(rows.begin(), rows.end(), t_cam_ns,
                                   [](const CalibrationLogRow &r, int64_t t) { return r.t_cam_ns < t; });
  return it == rows.end() ? &rows.back() : &*it;
}

Eigen::Matrix3d mat3(const double *a) {
  Eigen::Matrix3d m;
  for (int i = 0; i < 9; ++i)
    m(i / 3, i % 3) = a[i];
  return m;
}

std::vector<ovton::core::ImuData> imu_through_calibration(const std::vector<ovton::core::ImuData> &imu,
                                                          const std::vector<CalibrationLogRow> &rows) {
  std::vector<ovton::core::ImuData> out = imu;
  if (rows.empty())
    return out;
  for (auto &m : out) {
    const CalibrationLogRow *c =
        calibration_at(rows, m.t_imu_ns - static_cast<int64_t>(1e9 * rows.front().td_s)); // t_cam = t_imu − t_d
    m.wm = mat3(c->D_w) * m.wm;
    m.am = mat3(c->D_a) * m.am;
  }
  return out;
}

Eigen::Vector3d gyro_at(const std::vector<ovton::core::ImuData> &imu, double t_ns) {
  const auto it = std::lower_bound(imu.begin(), imu.end(), t_ns,
                                   [](const ovton::core::ImuData &m, double t) { return double(m.t_imu_ns) < t; });
  if (it == imu.begin())
    return imu.front().wm;
  if (it == imu.end())
    return imu.back().wm;
  const auto &a = *(it - 1), &b = *it;
  const double u = (t_ns - double(a.t_imu_ns)) / double(b.t_imu_ns - a.t_imu_ns);
  return a.wm + u * (b.wm - a.wm);
}

Eigen::Matrix3d body_rotation(const std::vector<ovton::core::ImuData> &imu, double t0_ns, double t1_ns,
                              const Eigen::Vector3d &bias) {
  const double span = 1e-9 * (t1_ns - t0_ns);
  const int steps = std::max(1, static_cast<int>(std::abs(span) / 1e-3));
  const double dt = span / steps;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  for (int k = 0; k < steps; ++k)
    R = R * ovton::core::so3_exp((gyro_at(imu, t0_ns + 1e9 * (k + 0.5) * dt) - bias) * dt);
  return R;
}

double focal_estimate(const CalibrationLogRow &row, double fu, double fv) {
  if (!(row.estimated & CalibrationLogRow::kIntrinsics) || !(fu > 0 && fv > 0))
    return 0.0;
  return 0.5 * (row.intrinsics[0] / fu + row.intrinsics[1] / fv) - 1.0;
}

} // namespace ovton::eval::diag
