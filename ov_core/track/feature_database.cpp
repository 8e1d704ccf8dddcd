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

/// An observation, with its constant-speed velocity (paper eq. 2) from `prev` when there is one.
FeatureObservation observation_after(const FeatureObservation *prev, int64_t t_cam_ns, const Eigen::Vector2d &uv,
                                     const Eigen::Vector2d &xy) {
  FeatureObservation o;
  o.t_cam_ns = t_cam_ns;
  o.uv = uv;
  o.xy = xy;
  if (prev) {
    // Difference in int64 first: stamps near 1.4e18 ns would lose the nanoseconds as doubles.
    const double dt = static_cast<double>(t_cam_ns - prev->t_cam_ns) * 1e-9;
    o.vel_uv = (uv - prev->uv) / dt;
    o.vel_xy = (xy - prev->xy) / dt;
    o.vel_valid = true;
  }
  return o;
}

void erase_older(std::vector<FeatureObservation> &obs, int64_t t_cam_ns) {
  obs.erase(obs.begin(), first_not_older(obs, t_cam_ns));
}

void erase_at(std::vector<FeatureObservation> &obs, int64_t t_cam_ns) {
  const auto pos = first_not_older(obs, t_cam_ns);
  if (pos != obs.end() && pos->t_cam_ns == t_cam_ns)
    obs.erase(pos);
}

} // namespace

const FeatureObservation *Feature::at(int64_t t_cam_ns) const {
  const auto it = std::lower_bound(obs.begin(), obs.end(), t_cam_ns,
                                   [](const FeatureObservation &o, int64_t t) { return o.t_cam_ns < t; });
  return (it != obs.end() && it->t_cam_ns == t_cam_ns) ? &*it : nullptr;
}

void FeatureDatabase::add_observation(size_t id, int64_t t_cam_ns, const Eigen::Vector2d &uv, const Eigen::Vector2d &xy,
                                      int cam) {
  if (!uv.allFinite() || !xy.allFinite())
    throw UsageError("FeatureDatabase: non-finite coordinates for feature " + std::to_string(id) + " at t_cam_ns " +
                     std::to_string(t_cam_ns));
  if (cam < 0)
    throw UsageError("FeatureDatabase: negative camera index");
  auto [it, inserted] = features_.try_emplace(id);
  Feature &feature = it->second;
  if (inserted) {
    feature.id = id;
    feature.obs.reserve(obs_capacity_);
  }
  if (cam > 0 && feature.more.size() < static_cast<size_t>(cam))
    feature.more.resize(static_cast<size_t>(cam));
  Feature &f = cam == 0 ? feature : feature.more[static_cast<size_t>(cam - 1)];
  if (cam > 0 && f.obs.empty()) {
    f.id = id;
    f.obs.reserve(obs_capacity_);
  }
  if (!f.obs.empty() && t_cam_ns <= f.obs.back().t_cam_ns)
    throw UsageError("FeatureDatabase: observation of feature " + std::to_string(id) + " at t_cam_ns " +
                     std::to_string(t_cam_ns) + " is not after its newest one (" +
                     std::to_string(f.obs.back().t_cam_ns) + ")");
  const FeatureObservation *prev_ptr = f.obs.empty() ? nullptr : &f.obs.back();
  if (cam == 0) {
    auto ghost = inserted ? last_seen_.find(id) : last_seen_.end();
    if (ghost != last_seen_.end() && ghost->second.t_cam_ns < t_cam_ns)
      prev_ptr = &ghost->second;
    f.obs.push_back(observation_after(prev_ptr, t_cam_ns, uv, xy));
    if (ghost != last_seen_.end())
      last_seen_.erase(ghost);
    return;
  }
  auto ghost = last_seen_more_.find(id);
  if (!prev_ptr && ghost != last_seen_more_.end() && ghost->second.size() >= static_cast<size_t>(cam)) {
    const FeatureObservation &g = ghost->second[static_cast<size_t>(cam - 1)];
    if (g.t_cam_ns >= 0 && g.t_cam_ns < t_cam_ns)
      prev_ptr = &g;
  }
  f.obs.push_back(observation_after(prev_ptr, t_cam_ns, uv, xy));
  if (ghost != last_seen_more_.end() && ghost->second.size() >= static_cast<size_t>(cam))
    ghost->second[static_cast<size_t>(cam - 1)].t_cam_ns = -1;
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
  for (auto it = last_seen_more_.begin(); it != last_seen_more_.end();) {
    bool any = false;
    for (auto &o : it->second) {
      if (o.t_cam_ns < t_cam_ns)
        o.t_cam_ns = -1;
      any = any || o.t_cam_ns >= 0;
    }
    it = any ? std::next(it) : last_seen_more_.erase(it);
  }
  for (auto it = features_.begin(); it != features_.end();) {
    erase_older(it->second.obs, t_cam_ns);
    for (auto &track : it->second.more)
      erase_older(track.obs, t_cam_ns);
    it = it->second.obs.empty() ? features_.erase(it) : std::next(it);
  }
}

void FeatureDatabase::remove_observations_at(int64_t t_cam_ns) {
  for (auto it = features_.begin(); it != features_.end();) {
    erase_at(it->second.obs, t_cam_ns);
    for (auto &track : it->second.more)
      erase_at(track.obs, t_cam_ns);
    it = it->second.obs.empty() ? features_.erase(it) : std::next(it);
  }
}

bool FeatureDatabase::remove(size_t id) {
  const auto it = features_.find(id);
  if (it == features_.end())
    return false;
  // The tracker may go on following this id; its next observation still has a velocity with respect to this one.
  if (!it->second.obs.empty())
    last_seen_[id] = it->second.obs.back();
  if (!it->second.more.empty()) {
    std::vector<FeatureObservation> &seen = last_seen_more_[id];
    seen.resize(it->second.more.size());
    for (size_t k = 0; k < seen.size(); ++k)
      if (!it->second.more[k].obs.empty())
        seen[k] = it->second.more[k].obs.back();
      else
        seen[k].t_cam_ns = -1;
  }
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
