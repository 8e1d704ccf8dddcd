#pragma once
// A trajectory's state at any time between its samples: ground-truth initialisation and NEES both need it.
#include "ov_core/types/sensor_data.h"

#include <algorithm>
#include <vector>

namespace ovton::core {

/// State at t, linear in position and velocity, slerp in rotation (biases and t_d from the earlier sample);
/// false outside the samples' span. `traj` must be sorted by time.
inline bool interpolate_state(const std::vector<StateSample> &traj, int64_t t, StateSample &out) {
  if (traj.size() < 2 || t < traj.front().t_ns || t > traj.back().t_ns)
    return false;
  auto it = std::lower_bound(traj.begin(), traj.end(), t, [](const StateSample &s, int64_t x) { return s.t_ns < x; });
  if (it == traj.begin()) {
    out = *it;
    return true;
  }
  const auto &b = *it, &a = *(it - 1);
  const double u = static_cast<double>(t - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  out = a;
  out.t_ns = t;
  out.p = (1 - u) * a.p + u * b.p;
  out.v = (1 - u) * a.v + u * b.v;
  out.q_WB = a.q_WB.slerp(u, b.q_WB);
  return true;
}

} // namespace ovton::core
