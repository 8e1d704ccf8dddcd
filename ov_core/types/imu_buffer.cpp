#include "ov_core/types/imu_buffer.h"
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
  if (t_.empty())
    return Eigen::Vector3d::Zero();
  if (t < t_.front())
    return c_.front() + (t - t_.front()) * w_.front();
  if (t > t_.back())
    return c_.back() + (t - t_.back()) * w_.back();
  const size_t i = std::min<size_t>(t_.size() - 2, std::upper_bound(t_.begin(), t_.end(), t) - t_.begin() - 1);
  const double h = t_[i + 1] - t_[i], u = t - t_[i];
  return c_[i] + u * w_[i] + 0.5 * u * u / h * (w_[i + 1] - w_[i]);
}

} // namespace ovton::core
