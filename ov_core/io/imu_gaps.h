#pragma once
// Gaps in an IMU log, as every reader judges them. Phones and USB IMUs drop packets: a gap of a few tens of
// milliseconds is propagated through (one longer integration step, whose process noise grows with its length as a
// gap's does), so it is counted and reported rather than refused. A gap long enough to lose the attitude is refused,
// but only where it matters: within the images' span (with a margin for the time offset); a gap long after the last
// image, or before the first, is never read.
#include "ov_core/types/sensor_data.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ovton::core {

/// What the log's gaps over the images' span were (Dataset::imu_gaps).
struct ImuGaps {
  long count = 0;              ///< gaps longer than 10 nominal periods, propagated through
  double longest_s = 0.0;      ///< the longest of them
  int64_t longest_at_ns = 0;   ///< IMU stamp of the reading that ends it
  std::string summary() const; ///< "" without gaps, else one sentence for a run's output
};

/// Longest gap within the images' span that is propagated through [s]; a longer one is refused.
inline constexpr double kMaxImuGapS = 0.25;

/// Scans n time-ordered IMU stamps (stamp(i) for i < n) over [images_begin_ns - 1 s, images_end_ns + 1 s]: counts the
/// gaps longer than 10 periods of rate_hz into `gaps` and returns the index of the reading after the first gap longer
/// than kMaxImuGapS there (n when there is none). Gaps outside the span are ignored. A stamp function, so that a reader
/// scans its messages where they are.
template <class Stamp>
size_t scan_imu_gaps(size_t n, Stamp &&stamp, int64_t images_begin_ns, int64_t images_end_ns, double rate_hz,
                     ImuGaps &gaps) {
  constexpr int64_t kMarginNs = 1000000000; // beyond any offset the search or a prior can give
  const int64_t lo = images_begin_ns - kMarginNs, hi = images_end_ns + kMarginNs;
  const int64_t counted_ns = rate_hz > 0 ? static_cast<int64_t>(10.0 / rate_hz * 1e9) : 100000000;
  const auto refused_ns = static_cast<int64_t>(kMaxImuGapS * 1e9);
  size_t refused = n;
  for (size_t i = 1; i < n; ++i) {
    const int64_t a = stamp(i - 1), b = stamp(i), dt = b - a;
    if (b < lo || a > hi || dt <= counted_ns)
      continue;
    if (dt > refused_ns && refused == n)
      refused = i;
    ++gaps.count;
    if (dt * 1e-9 > gaps.longest_s) {
      gaps.longest_s = dt * 1e-9;
      gaps.longest_at_ns = b;
    }
  }
  return refused;
}

/// One sentence when the readings' median spacing and the calibration's stated rate (`rate_hz`, named by
/// `rate_source`) differ by more than 20 %, "" otherwise. A factor of 3 or more is refused by the folder readers as a
/// unit error; between, the log is read (the filter integrates over the stamps' own spacing) and the user told, since
/// noise figures taken from a datasheet or a calibration at the stated rate may not be the IMU's as it runs.
std::string imu_rate_mismatch(const std::vector<ImuData> &imu, double rate_hz, const std::string &rate_source);

} // namespace ovton::core
