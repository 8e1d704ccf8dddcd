#include "ov_core/io/imu_gaps.h"

#include <cstdio>

namespace ovton::core {

std::string ImuGaps::summary() const {
  if (count == 0)
    return "";
  char s[200];
  std::snprintf(s, sizeof s, "%ld IMU gap%s within the images' span (longest %.0f ms), propagated through", count,
                count == 1 ? "" : "s", longest_s * 1e3);
  return s;
}

size_t scan_imu_gaps(const std::vector<ImuData> &imu, int64_t images_begin_ns, int64_t images_end_ns, double rate_hz,
                     ImuGaps &gaps) {
  constexpr int64_t kMarginNs = 1000000000; // beyond any offset the search or a prior can give
  const int64_t lo = images_begin_ns - kMarginNs, hi = images_end_ns + kMarginNs;
  const int64_t counted_ns = rate_hz > 0 ? static_cast<int64_t>(10.0 / rate_hz * 1e9) : 100000000;
  const auto refused_ns = static_cast<int64_t>(kMaxImuGapS * 1e9);
  size_t refused = imu.size();
  for (size_t i = 1; i < imu.size(); ++i) {
    const int64_t a = imu[i - 1].t_imu_ns, b = imu[i].t_imu_ns, dt = b - a;
    if (b < lo || a > hi || dt <= counted_ns)
      continue;
    if (dt > refused_ns && refused == imu.size())
      refused = i;
    ++gaps.count;
    if (dt * 1e-9 > gaps.longest_s) {
      gaps.longest_s = dt * 1e-9;
      gaps.longest_at_ns = b;
    }
  }
  return refused;
}

} // namespace ovton::core
