#include "ov_core/track/feature_database.h"
#include "ov_core/types/errors.h"

#include <algorithm>
#include <string>

namespace ovton::core {

namespace {

void sort_by_id(std::vector<const Feature *> &out) {
  std::sort(out.begin(), out.end(), [](const Feature *a, const Feature *b) { return a->id < b->id; });
}

/// Observations are time-ordered, so the first one not older than t splits the vector.
std::vector<FeatureObservation>::iterator first_not_older(std::vector<FeatureObservation> &obs, int64_t t_cam_ns) {
  return std::lower_bound(obs.begin(), obs.end(), t_cam_ns,
                          [](const FeatureObservation &o, int64_t t) { return o.t_cam_ns < t; });
}

} // namespace

const FeatureObservation *Feature::at(int64_t t_cam_ns) const {
  const auto it = std::lower_bound(obs.begin(), obs.end(), t_cam_ns,
                                   [](const FeatureObservation &o, int64_t t) { return o.t_cam_ns < t; });
  return (it != obs.end() && it->t_cam_ns == t_cam_ns) ? &*it : nullptr;
}

void FeatureDatabase::add_observation(size_t id, int64_t t_cam_ns, const Eigen::Vector2d &uv,
                                      const Eigen::Vector2d &xy) {
  if (!uv.allFinite() || !xy.allFinite())
    throw UsageError("FeatureDatabase: non-finite coordinates for feature " + std::to_string(id) + " at t_cam_ns " +
                     std::to_string(t_cam_ns));
  auto [it, inserted] = features_.try_emplace(id);
  Feature &f = it->second;
  if (inserted) {
    f.id = id;
    f.obs.reserve(obs_capacity_);
  } else if (!f.obs.empty() && t_cam_ns <= f.obs.back().t_cam_ns) {
    throw UsageError("FeatureDatabase: observation of feature " + std::to_string(id) + " at t_cam_ns " +
                     std::to_string(t_cam_ns) + " is not after its newest one (" +
                     std::to_string(f.obs.back().t_cam_ns) + ")");
  }
  FeatureObservation o;
  o.t_cam_ns = t_cam_ns;
  o.uv = uv;
  o.xy = xy;
  const FeatureObservation *prev_ptr = f.obs.empty() ? nullptr : &f.obs.back();
  auto ghost = inserted ? last_seen_.find(id) : last_seen_.end();
  if (ghost != last_seen_.end() && ghost->second.t_cam_ns < t_cam_ns)
    prev_ptr = &ghost->second;
  if (prev_ptr) {
    const FeatureObservation &prev = *prev_ptr;
    // Difference in int64 first: stamps near 1.4e18 ns would lose the nanoseconds as doubles.
    const double dt = static_cast<double>(t_cam_ns - prev.t_cam_ns) * 1e-9;
    o.vel_uv = (uv - prev.uv) / dt;
    o.vel_xy = (xy - prev.xy) / dt;
    o.vel_valid = true;
  }
  f.obs.push_back(o);
  if (ghost != last_seen_.end())
    last_seen_.erase(ghost);
}

void FeatureDatabase::lost_features(int64_t t_newest_cam_ns, std::vector<const Feature *> &out) const {
  out.clear();
  for (const auto &kv : features_)
    if (!kv.second.obs.empty() && kv.second.obs.back().t_cam_ns < t_newest_cam_ns)
      out.push_back(&kv.second);
  sort_by_id(out);
}

void FeatureDatabase::features_older_than(int64_t t_cam_ns, std::vector<const Feature *> &out) const {
  out.clear();
  for (const auto &kv : features_)
    if (!kv.second.obs.empty() && kv.second.obs.front().t_cam_ns < t_cam_ns)
      out.push_back(&kv.second);
  sort_by_id(out);
}

void FeatureDatabase::features_observed_at(int64_t t_cam_ns, std::vector<const Feature *> &out) const {
  out.clear();
  for (const auto &kv : features_)
    if (kv.second.at(t_cam_ns))
      out.push_back(&kv.second);
  sort_by_id(out);
}

void FeatureDatabase::remove_observations_older_than(int64_t t_cam_ns) {
  for (auto it = last_seen_.begin(); it != last_seen_.end();)
    it = it->second.t_cam_ns < t_cam_ns ? last_seen_.erase(it) : std::next(it);
  for (auto it = features_.begin(); it != features_.end();) {
    auto &obs = it->second.obs;
    obs.erase(obs.begin(), first_not_older(obs, t_cam_ns));
    it = obs.empty() ? features_.erase(it) : std::next(it);
  }
}

void FeatureDatabase::remove_observations_at(int64_t t_cam_ns) {
  for (auto it = features_.begin(); it != features_.end();) {
    auto &obs = it->second.obs;
    const auto pos = first_not_older(obs, t_cam_ns);
    if (pos != obs.end() && pos->t_cam_ns == t_cam_ns)
      obs.erase(pos);
    it = obs.empty() ? features_.erase(it) : std::next(it);
  }
}

bool FeatureDatabase::remove(size_t id) {
  const auto it = features_.find(id);
  if (it == features_.end())
    return false;
  // The tracker may go on following this id; its next observation still has a velocity with respect to this one.
  if (!it->second.obs.empty())
    last_seen_[id] = it->second.obs.back();
  features_.erase(it);
  return true;
}

const Feature *FeatureDatabase::get(size_t id) const {
  const auto it = features_.find(id);
  return it == features_.end() ? nullptr : &it->second;
}

size_t FeatureDatabase::num_observations() const {
  size_t n = 0;
  for (const auto &kv : features_)
    n += kv.second.obs.size();
  return n;
}

} // namespace ovton::core
