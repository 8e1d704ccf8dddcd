#include "ov_core/types/imu_buffer.h"
#include "ov_core/math/so3.h"
#include "ov_core/types/errors.h"

#include <algorithm>

namespace ovton::core {

ImuBuffer::ImuBuffer(const std::vector<ImuData> &readings) {
  for (const auto &m : readings)
    push(m);
}

void ImuBuffer::push(const ImuData &m) {
  if (!buf_.empty() && m.t_imu_ns <= buf_.back().t_imu_ns)
    throw UsageError("IMU readings must arrive in increasing time order");
  buf_.push_back(m);
}

void ImuBuffer::keep_span(int64_t span_ns) {
  while (buf_.size() > 2 && buf_.back().t_imu_ns - buf_[1].t_imu_ns > span_ns)
    buf_.pop_front();
}

void ImuBuffer::drop_before(int64_t t_ns) {
  while (buf_.size() > 1 && buf_[1].t_imu_ns <= t_ns)
    buf_.pop_front();
}

size_t ImuBuffer::first_after(int64_t t_ns) const {
  return static_cast<size_t>(
      std::upper_bound(buf_.begin(), buf_.end(), t_ns, [](int64_t t, const ImuData &m) { return t < m.t_imu_ns; }) -
      buf_.begin());
}

bool ImuBuffer::interpolate(int64_t t_ns, ImuData &out) const {
  if (buf_.empty() || t_ns < buf_.front().t_imu_ns || t_ns > buf_.back().t_imu_ns)
    return false;
  auto it =
      std::lower_bound(buf_.begin(), buf_.end(), t_ns, [](const ImuData &m, int64_t t) { return m.t_imu_ns < t; });
  if (it->t_imu_ns == t_ns) {
    out = *it;
    return true;
  }
  const auto &b = *it, &a = *(it - 1);
  const double u = static_cast<double>(t_ns - a.t_imu_ns) / static_cast<double>(b.t_imu_ns - a.t_imu_ns);
  out.t_imu_ns = t_ns;
  out.wm = (1 - u) * a.wm + u * b.wm;
  out.am = (1 - u) * a.am + u * b.am;
  return true;
}

Eigen::Vector3d ImuBuffer::gyro_at(double t_ns) const {
  const auto it = std::lower_bound(buf_.begin(), buf_.end(), t_ns,
                                   [](const ImuData &m, double t) { return static_cast<double>(m.t_imu_ns) < t; });
  if (it == buf_.begin())
    return buf_.front().wm;
  if (it == buf_.end())
    return buf_.back().wm;
  const auto &a = *(it - 1), &b = *it;
  const double u = (t_ns - static_cast<double>(a.t_imu_ns)) / static_cast<double>(b.t_imu_ns - a.t_imu_ns);
  return a.wm + u * (b.wm - a.wm);
}

bool ImuBuffer::mean_gyro_readings(int64_t t_from_ns, int64_t t_to_ns, Eigen::Vector3d &w) const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  auto it =
      std::lower_bound(buf_.begin(), buf_.end(), t_from_ns, [](const ImuData &m, int64_t t) { return m.t_imu_ns < t; });
  for (; it != buf_.end() && it->t_imu_ns <= t_to_ns; ++it)
    sum += it->wm, ++n;
  if (n == 0)
    return false;
  w = sum / n;
  return true;
}

std::optional<Eigen::Matrix3d> ImuBuffer::rotation(int64_t a, int64_t b) const {
  if (b <= a || buf_.size() < 2 || a < buf_.front().t_imu_ns || b > buf_.back().t_imu_ns)
    return std::nullopt;
  size_t k = first_after(a) - 1; // t_k <= a < t_{k+1}
  const auto rate_at = [&](size_t i, int64_t t) -> Eigen::Vector3d {
    const double span = static_cast<double>(buf_[i + 1].t_imu_ns - buf_[i].t_imu_ns);
    const double s = span > 0 ? static_cast<double>(t - buf_[i].t_imu_ns) / span : 0.0;
    return (1.0 - s) * buf_[i].wm + s * buf_[i + 1].wm;
  };
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  int64_t t = a;
  while (t < b && k + 1 < buf_.size()) {
    const int64_t t_end = std::min(b, buf_[k + 1].t_imu_ns);
    if (t_end > t) {
      const Eigen::Vector3d w = 0.5 * (rate_at(k, t) + rate_at(k, t_end));
      R = R * so3_exp(w * (static_cast<double>(t_end - t) * 1e-9));
    }
    t = t_end;
    ++k;
  }
  return R;
}

GyroIntegral::GyroIntegral(const ImuBuffer &imu, int64_t t0_ns) {
  t_.reserve(imu.size());
  w_.reserve(imu.size());
  for (const auto &m : imu) {
    t_.push_back(ns_to_s(m.t_imu_ns - t0_ns));
    w_.push_back(m.wm);
  }
  c_.assign(t_.size(), Eigen::Vector3d::Zero());
  for (size_t i = 1; i < t_.size(); ++i)
    c_[i] = c_[i - 1] + 0.5 * (t_[i] - t_[i - 1]) * (w_[i] + w_[i - 1]);
}

Eigen::Vector3d GyroIntegral::integral(double t) const {
  const size_t i = std::min<size_t>(t_.size() - 2, std::upper_bound(t_.begin(), t_.end(), t) - t_.begin() - 1);
  const double h = t_[i + 1] - t_[i], u = t - t_[i];
  return c_[i] + u * w_[i] + 0.5 * u * u / h * (w_[i + 1] - w_[i]);
}

} // namespace ovton::core
