#include "ov_core/io/imu_gaps.h"

#include <algorithm>
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

std::string imu_rate_mismatch(const std::vector<ImuData> &imu, double rate_hz, const std::string &rate_source) {
  if (imu.size() < 3 || !(rate_hz > 0))
    return "";
  std::vector<int64_t> dt(imu.size() - 1);
  for (size_t i = 1; i < imu.size(); ++i)
    dt[i - 1] = imu[i].t_imu_ns - imu[i - 1].t_imu_ns;
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  const double median_s = dt[dt.size() / 2] * 1e-9, ratio = median_s * rate_hz;
  if (ratio > 1 / 1.2 && ratio < 1.2)
    return "";
  char s[400];
  std::snprintf(s, sizeof s,
                "the IMU readings are %.3g ms apart (median: %.4g Hz) but %s says %.4g Hz: the filter integrates over "
                "the stamps' own spacing; check that the IMU noise densities are the IMU's as it runs",
                median_s * 1e3, 1 / median_s, rate_source.c_str(), rate_hz);
  return s;
}

} // namespace ovton::core
