#include "ov_eval/diagnose/filter_calibration.h"
#include "ov_core/types/imu_buffer.h"

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
  return ovton::core::imu_gyro_at(imu, t_ns);
}

Eigen::Matrix3d body_rotation(const std::vector<ovton::core::ImuData> &imu, double t0_ns, double t1_ns,
                              const Eigen::Vector3d &bias) {
  if (t1_ns < t0_ns)
    return body_rotation(imu, t1_ns, t0_ns, bias).transpose();
  const int64_t a = std::llround(t0_ns), b = std::llround(t1_ns);
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  if (imu.empty() || b <= a)
    return R;
  // Beyond the readings the rate is held at the end one.
  const int64_t lo = imu.front().t_imu_ns, hi = imu.back().t_imu_ns;
  if (a < lo)
    R = ovton::core::so3_exp((imu.front().wm - bias) * (1e-9 * double(std::min(b, lo) - a)));
  if (const auto inside = ovton::core::imu_rotation(imu, std::max(a, lo), std::min(b, hi), bias))
    R = R * *inside;
  if (b > hi)
    R = R * ovton::core::so3_exp((imu.back().wm - bias) * (1e-9 * double(b - std::max(a, hi))));
  return R;
}

double focal_estimate(const CalibrationLogRow &row, double fu, double fv) {
  if (!(row.estimated & CalibrationLogRow::kIntrinsics) || !(fu > 0 && fv > 0))
    return 0.0;
  return 0.5 * (row.intrinsics[0] / fu + row.intrinsics[1] / fv) - 1.0;
}

} // namespace ovton::eval::diag
