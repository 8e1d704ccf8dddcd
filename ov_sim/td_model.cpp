#include "ov_sim/td_model.h"
#include "ov_core/types/errors.h"
#include "ov_sim/random.h"
#include <cmath>

namespace ovton::sim {

TdModelKind parse_td_model(const std::string &name) {
  if (name == "constant")
    return TdModelKind::Constant;
  if (name == "drift")
    return TdModelKind::Drift;
  if (name == "wander")
    return TdModelKind::Wander;
  throw ovton::core::UsageError("unknown time-offset model '" + name + "' (expected constant, drift or wander)");
}

std::string to_string(TdModelKind k) {
  return k == TdModelKind::Constant ? "constant" : k == TdModelKind::Drift ? "drift" : "wander";
}

std::vector<TimedImage> apply_td_model(const std::vector<int64_t> &t_imu_ns, const TdModelOptions &opt) {
  if (opt.kind == TdModelKind::Wander && !(opt.wander_period_s > 0.0 && std::isfinite(opt.wander_amplitude_s)))
    throw ovton::core::UsageError("time-offset model wander: the period must be positive and the amplitude finite");
  Rng rng(opt.seed);
  std::vector<TimedImage> out;
  out.reserve(t_imu_ns.size());
  double td = opt.td0_s;
  for (size_t k = 0; k < t_imu_ns.size(); ++k) {
    if (k > 0) {
      const double dt = ovton::core::ns_to_s(t_imu_ns[k] - t_imu_ns[k - 1]);
      if (!(dt > 0.0))
        throw ovton::core::UsageError("time-offset model: image times must be strictly increasing");
      if (opt.kind == TdModelKind::Drift)
        td += opt.bias_s_per_s * dt + opt.noise_s_per_sqrt_s * std::sqrt(dt) * rng.normal();
      if (opt.kind == TdModelKind::Wander)
        td = opt.td0_s +
             opt.wander_amplitude_s *
                 std::sin(2.0 * M_PI * ovton::core::ns_to_s(t_imu_ns[k] - t_imu_ns[0]) / opt.wander_period_s);
    }
    TimedImage im;
    im.t_imu_ns = t_imu_ns[k];
    im.td_ns = ovton::core::s_to_ns(td);
    im.t_cam_ns = im.t_imu_ns - im.td_ns;
    if (!out.empty() && im.t_cam_ns <= out.back().t_cam_ns)
      throw ovton::core::UsageError("time-offset model: camera stamps would not increase at image " +
                                    std::to_string(k) + " (offset noise too large for the frame interval)");
    out.push_back(im);
  }
  return out;
}

} // namespace ovton::sim
