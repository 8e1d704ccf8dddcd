#pragma once
// The IMU between two times, read one way everywhere: the propagator, the tracker's gyro prior, the coarse t_d search
// and diagnose all ask this buffer (or its running integral) instead of walking readings of their own. Between two
// readings the rates are linear in time (the readings are samples of a smooth signal); outside the readings a query
// either fails or, where a caller says so, holds the end reading.
#include "ov_core/types/sensor_data.h"

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

namespace ovton::core {

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
  /// The gyro at a fractional time, linear between readings and held at the ends (diagnose's fits).
  Eigen::Vector3d gyro_at(double t_ns) const;
  /// The mean of the gyro readings inside [t_from_ns, t_to_ns] (readings, not time-weighted: a window centred on an
  /// image takes the vibration out of the body rate there); false when the window holds none.
  bool mean_gyro_readings(int64_t t_from_ns, int64_t t_to_ns, Eigen::Vector3d &w) const;
  /// R_{I(a) I(b)}: the body's rotation from t_a to t_b (IMU clock), each piece between readings turned by its mean
  /// rate (trapezoid of the linear rates). Empty when b <= a or the readings do not cover [a, b].
  std::optional<Eigen::Matrix3d> rotation(int64_t t_a_ns, int64_t t_b_ns) const;

  /// Cuts [t_from_ns, t_to_ns] at the readings inside it and calls step(w_mean, a_mean, dt) for each piece, with the
  /// readings interpolated at both ends and each piece's rates the mean of its two ends. Returns false (calling
  /// nothing) when the buffer does not cover the interval; true for an empty one.
  template <typename StepFn> bool for_each_piece(int64_t t_from_ns, int64_t t_to_ns, StepFn &&step) const;

private:
  std::deque<ImuData> buf_;
};

/// The gyro's running integral from the first reading, on seconds after a time origin: the mean rate over any
/// interval costs two lookups (the coarse t_d search asks every image pair's mean at every candidate offset).
class GyroIntegral {
public:
  GyroIntegral(const ImuBuffer &imu, int64_t t0_ns);
  GyroIntegral(const std::vector<ImuData> &imu, int64_t t0_ns) : GyroIntegral(ImuBuffer(imu), t0_ns) {}
  /// First and last reading [s after the origin].
  double begin() const { return t_.empty() ? 0.0 : t_.front(); }
  double end() const { return t_.empty() ? 0.0 : t_.back(); }
  /// Mean rate over [a, b] [s after the origin], a < b, both inside the readings.
  Eigen::Vector3d mean(double a, double b) const { return (integral(b) - integral(a)) / (b - a); }
  /// The angle turned from the first reading to t (t inside the readings).
  Eigen::Vector3d integral(double t) const;

private:
  std::vector<double> t_;
  std::vector<Eigen::Vector3d> w_, c_;
};

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
