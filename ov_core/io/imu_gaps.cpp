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

} // namespace ovton::core
