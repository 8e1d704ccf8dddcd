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

/// Scans `imu` (time-ordered) over [images_begin_ns - 1 s, images_end_ns + 1 s]: counts the gaps longer than 10 periods
/// of rate_hz into `gaps` and returns the index of the reading after the first gap longer than kMaxImuGapS there
/// (imu.size() when there is none). Gaps outside the span are ignored.
size_t scan_imu_gaps(const std::vector<ImuData> &imu, int64_t images_begin_ns, int64_t images_end_ns, double rate_hz,
                     ImuGaps &gaps);

} // namespace ovton::core
