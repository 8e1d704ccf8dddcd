#pragma once
// The IMU between two times, read one way everywhere: the propagator, the tracker's gyro prior, the coarse t_d search
// and diagnose all ask this buffer (or its running integral) instead of walking readings of their own. Between two
// readings the rates are linear in time (the readings are samples of a smooth signal); outside the readings a query
// either fails or, where a caller says so, holds the end reading.
#include "ov_core/math/so3.h"
#include "ov_core/types/sensor_data.h"

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

namespace ovton::core {

/// The gyro at a fractional time in time-ordered `readings` (any random-access container of ImuData), linear between
/// readings and held at the ends.
template <typename Readings> Eigen::Vector3d imu_gyro_at(const Readings &readings, double t_ns);
/// R_{I(a) I(b)} over time-ordered `readings`: each piece between readings turned by its mean rate less `bias`
/// (trapezoid of the linear rates). Empty when b <= a or the readings do not cover [a, b].
template <typename Readings>
std::optional<Eigen::Matrix3d> imu_rotation(const Readings &readings, int64_t t_a_ns, int64_t t_b_ns,
                                            const Eigen::Vector3d &bias = Eigen::Vector3d::Zero());

class ImuBuffer {
public:
  ImuBuffer() = default;
  /// Time-ordered readings; throws UsageError at the first one not after the one before.
  explicit ImuBuffer(const std::vector<ImuData> &readings);

  /// Appends a reading; throws UsageError unless it is after the last one.
  void push(const ImuData &m);
  /// Forgets the oldest readings while the second one is more than span_ns before the newest (the first stays, so
  /// that an interpolation at the start of the span still has a reading before it).
  void keep_span(int64_t span_ns);
  /// Forgets the readings before t_ns, all but the last one at or before it.
  void drop_before(int64_t t_ns);

  bool empty() const { return buf_.empty(); }
  size_t size() const { return buf_.size(); }
  const ImuData &front() const { return buf_.front(); }
  const ImuData &back() const { return buf_.back(); }
  const ImuData &operator[](size_t i) const { return buf_[i]; }
  std::deque<ImuData>::const_iterator begin() const { return buf_.begin(); }
  std::deque<ImuData>::const_iterator end() const { return buf_.end(); }
  /// Index of the first reading after t_ns (size() when there is none).
  size_t first_after(int64_t t_ns) const;

  /// The reading at t_ns, linear between the two around it; false outside [front, back].
  bool interpolate(int64_t t_ns, ImuData &out) const;
  /// The gyro at a fractional time, linear between readings and held at the ends.
  Eigen::Vector3d gyro_at(double t_ns) const { return imu_gyro_at(buf_, t_ns); }
  /// The mean of the gyro readings inside [t_from_ns, t_to_ns] (readings, not time-weighted: a window centred on an
  /// image takes the vibration out of the body rate there); false when the window holds none.
  bool mean_gyro_readings(int64_t t_from_ns, int64_t t_to_ns, Eigen::Vector3d &w) const;
  /// R_{I(a) I(b)}: the body's rotation from t_a to t_b (IMU clock), imu_rotation over the buffer.
  std::optional<Eigen::Matrix3d> rotation(int64_t t_a_ns, int64_t t_b_ns) const {
    return imu_rotation(buf_, t_a_ns, t_b_ns);
  }

  /// Cuts [t_from_ns, t_to_ns] at the readings inside it and calls step(w_mean, a_mean, dt) for each piece, with the
  /// readings interpolated at both ends and each piece's rates the mean of its two ends. Returns false (calling
  /// nothing) when the buffer does not cover the interval; true for an empty one.
  template <typename StepFn> bool for_each_piece(int64_t t_from_ns, int64_t t_to_ns, StepFn &&step) const;

private:
  std::deque<ImuData> buf_;
};

/// The gyro's running integral from the first reading, on seconds after a time origin: the mean rate over any
/// interval costs two lookups (the coarse t_d search asks every image pair's mean at every candidate offset). Outside
/// the readings the rate is held at the end reading.
class GyroIntegral {
public:
  GyroIntegral(const ImuBuffer &imu, int64_t t0_ns);
  GyroIntegral(const std::vector<ImuData> &imu, int64_t t0_ns) : GyroIntegral(ImuBuffer(imu), t0_ns) {}
  /// First and last reading [s after the origin].
  double begin() const { return t_.empty() ? 0.0 : t_.front(); }
  double end() const { return t_.empty() ? 0.0 : t_.back(); }
  /// Mean rate over [a, b] [s after the origin], a < b.
  Eigen::Vector3d mean(double a, double b) const { return (integral(b) - integral(a)) / (b - a); }
  /// The angle turned from the first reading to t.
  Eigen::Vector3d integral(double t) const;

private:
  std::vector<double> t_;
  std::vector<Eigen::Vector3d> w_, c_;
};

template <typename Readings> Eigen::Vector3d imu_gyro_at(const Readings &imu, double t_ns) {
  const auto it = std::lower_bound(imu.begin(), imu.end(), t_ns,
                                   [](const ImuData &m, double t) { return static_cast<double>(m.t_imu_ns) < t; });
  if (it == imu.begin())
    return imu.front().wm;
  if (it == imu.end())
    return imu.back().wm;
  const auto &a = *(it - 1), &b = *it;
  const double u = (t_ns - static_cast<double>(a.t_imu_ns)) / static_cast<double>(b.t_imu_ns - a.t_imu_ns);
  return a.wm + u * (b.wm - a.wm);
}

template <typename Readings>
std::optional<Eigen::Matrix3d> imu_rotation(const Readings &imu, int64_t a, int64_t b, const Eigen::Vector3d &bias) {
  if (b <= a || imu.size() < 2 || a < imu.front().t_imu_ns || b > imu.back().t_imu_ns)
    return std::nullopt;
  // t_k <= a < t_{k+1}
  size_t k = static_cast<size_t>(std::upper_bound(imu.begin(), imu.end(), a,
                                                  [](int64_t t, const ImuData &m) { return t < m.t_imu_ns; }) -
                                 imu.begin()) -
             1;
  const auto rate_at = [&](size_t i, int64_t t) -> Eigen::Vector3d {
    const double span = static_cast<double>(imu[i + 1].t_imu_ns - imu[i].t_imu_ns);
    const double s = span > 0 ? static_cast<double>(t - imu[i].t_imu_ns) / span : 0.0;
    return (1.0 - s) * imu[i].wm + s * imu[i + 1].wm - bias;
  };
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  int64_t t = a;
  while (t < b && k + 1 < imu.size()) {
    const int64_t t_end = std::min(b, imu[k + 1].t_imu_ns);
    if (t_end > t) {
      const Eigen::Vector3d w = 0.5 * (rate_at(k, t) + rate_at(k, t_end));
      R = R * so3_exp(w * (static_cast<double>(t_end - t) * 1e-9));
    }
    t = t_end;
    ++k;
  }
  return R;
}

template <typename StepFn> bool ImuBuffer::for_each_piece(int64_t t_from, int64_t t_to, StepFn &&step) const {
  if (t_to <= t_from)
    return t_to == t_from;
  ImuData prev;
  if (!interpolate(t_from, prev) || buf_.back().t_imu_ns < t_to)
    return false;
  auto it = buf_.begin() + static_cast<std::ptrdiff_t>(first_after(t_from));
  while (true) {
    ImuData next;
    if (it != buf_.end() && it->t_imu_ns < t_to) {
      next = *it++;
    } else {
      interpolate(t_to, next);
    }
    const double dt = ns_to_s(next.t_imu_ns - prev.t_imu_ns);
    if (dt > 0)
      step(0.5 * (prev.wm + next.wm), 0.5 * (prev.am + next.am), dt);
    prev = next;
    if (next.t_imu_ns >= t_to)
      return true;
  }
}

} // namespace ovton::core
