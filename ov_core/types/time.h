#pragma once
// The one place where stamps are converted and added. Every clock is int64 nanoseconds; a double of seconds that
// does not fit (NaN, inf, beyond ±292 years) or a sum that would overflow is reported instead of being undefined
// behaviour (a cast of inf to int64 and signed overflow are both UB, and both were reached from user input).
#include "ov_core/types/errors.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>

namespace ovton::core {

inline double ns_to_s(int64_t ns) {
  return static_cast<double>(ns) * 1e-9;
}

/// Seconds -> nanoseconds (rounded to nearest), or nothing when the value is not finite or its nanoseconds do not fit
/// in an int64. For readers that want to name the file and line themselves.
inline std::optional<int64_t> try_s_to_ns(double s) {
  // 9.2e18 ns is just below INT64_MAX (9.223e18); the rounding below then cannot overflow either.
  constexpr double kMaxNs = 9.2e18;
  if (!std::isfinite(s))
    return std::nullopt;
  const double ns = s * 1e9;
  if (!(std::abs(ns) < kMaxNs))
    return std::nullopt;
  return static_cast<int64_t>(ns >= 0 ? ns + 0.5 : ns - 0.5);
}

/// Seconds -> nanoseconds. Throws UsageError for a value that has no int64 nanosecond form (NaN, inf, |s| > 9.2e9).
inline int64_t s_to_ns(double s) {
  if (auto ns = try_s_to_ns(s))
    return *ns;
  throw UsageError("time value " + std::to_string(s) +
                   " s has no int64 nanosecond form (NaN, inf or beyond 292 years)");
}

/// a + b, or nothing on int64 overflow.
inline std::optional<int64_t> try_add_ns(int64_t a, int64_t b) {
  int64_t out = 0;
  if (__builtin_add_overflow(a, b, &out))
    return std::nullopt;
  return out;
}

/// An image's IMU-clock time t_cam + t_d (t_imu = t_cam + t_d), or nothing when it has none in the int64 clock.
inline std::optional<int64_t> try_imu_time_ns(int64_t t_cam_ns, double td_s) {
  const auto td_ns = try_s_to_ns(td_s);
  return td_ns ? try_add_ns(t_cam_ns, *td_ns) : std::nullopt;
}

/// a + b, held at the ends of the int64 clock instead of overflowing (for times that only bound a wait).
inline int64_t saturating_add_ns(int64_t a, int64_t b) {
  int64_t out = 0;
  if (__builtin_add_overflow(a, b, &out))
    return b > 0 ? std::numeric_limits<int64_t>::max() : std::numeric_limits<int64_t>::min();
  return out;
}

/// a + b. Throws UsageError on int64 overflow (a stamp near the end of the clock plus an offset).
inline int64_t add_ns(int64_t a, int64_t b) {
  if (auto r = try_add_ns(a, b))
    return *r;
  throw UsageError("time " + std::to_string(a) + " ns + " + std::to_string(b) + " ns overflows the int64 clock");
}

/// a − b. Throws UsageError on int64 overflow.
inline int64_t sub_ns(int64_t a, int64_t b) {
  int64_t out = 0;
  if (__builtin_sub_overflow(a, b, &out))
    throw UsageError("time " + std::to_string(a) + " ns - " + std::to_string(b) + " ns overflows the int64 clock");
  return out;
}

/// A decimal stamp split at the point ("1403715274.302142": whole seconds 1403715274 and the fraction as 302142000 ns)
/// -> ns without a double on the way (a double keeps only ~0.1 us at 1.4e9 s), or nothing when it does not fit.
/// `sec_abs` and `frac_ns` are magnitudes; `negative` is the sign of the whole value ("-0.5" has it on the fraction).
inline std::optional<int64_t> try_seconds_parts_to_ns(int64_t sec_abs, int64_t frac_ns, bool negative) {
  int64_t whole = 0;
  if (sec_abs < 0 || frac_ns < 0 || __builtin_mul_overflow(sec_abs, int64_t{1000000000}, &whole))
    return std::nullopt;
  auto sum = try_add_ns(whole, frac_ns);
  if (!sum)
    return std::nullopt;
  return negative ? -*sum : *sum;
}

} // namespace ovton::core
