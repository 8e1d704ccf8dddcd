#pragma once
// Every feature track the front end produced, with per-observation stamps, pixel and normalised coordinates and
// the image-plane velocity that the state-irrelevant time-offset model needs (TON-VIO paper eq. 2).
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace ovton::core {

/// One observation of a feature in one image, stamped in the camera clock.
struct FeatureObservation {
  int64_t t_cam_ns = 0;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero(); ///< distorted pixel, as tracked
  Eigen::Vector2d xy = Eigen::Vector2d::Zero(); ///< undistorted normalised (x/z, y/z)
  /// Constant-speed velocity from the previous observation of the same feature (paper eq. 2):
  /// (uv_k - uv_{k-1}) / (t_k - t_{k-1}) [px/s] and the same for xy [1/s]. Zero and invalid for a first
  /// observation, because a single point in time carries no speed.
  Eigen::Vector2d vel_uv = Eigen::Vector2d::Zero();
  Eigen::Vector2d vel_xy = Eigen::Vector2d::Zero();
  bool vel_valid = false;
};

/// One feature track: its observations in strictly increasing t_cam_ns.
struct Feature {
  size_t id = 0;
  std::vector<FeatureObservation> obs; ///< in the rig's primary camera (cam0)
  /// The same landmark in the rig's further cameras: more[k - 1] is camera k's track (same id, its own observations
  /// and velocities; an image of camera k carries the stamp of the primary image it pairs with). Empty for one camera.
  std::vector<Feature> more;

  const FeatureObservation &oldest() const { return obs.front(); }
  const FeatureObservation &newest() const { return obs.back(); }
  /// The observation stamped exactly t_cam_ns, or nullptr. Exact integer match: clones are keyed by ns.
  const FeatureObservation *at(int64_t t_cam_ns) const;
};

/// Feature tracks keyed by id. Not thread-safe: the front end and the estimator run in one thread here; add a
/// lock at the call site if the tracker moves to its own thread.
///
/// Query results are pointers into the database, sorted by id so that the estimator processes features in the
/// same order on every run. They stay valid until the feature they point to is removed (node-based storage, so
/// inserting other features does not move them).
class FeatureDatabase {
public:
  /// Observations reserved when a feature is created, so that a track of up to this length never reallocates.
  explicit FeatureDatabase(size_t obs_capacity = 16) : obs_capacity_(obs_capacity) {}

  /// Appends an observation of camera `cam` (0: the primary) to feature `id` (created if new) and computes its velocity
  /// from that camera's previous one. Throws UsageError when t_cam_ns is not strictly after the newest observation of
  /// the same camera or is not finite.
  void add_observation(size_t id, int64_t t_cam_ns, const Eigen::Vector2d &uv, const Eigen::Vector2d &xy, int cam = 0);

  /// Appends one frame of tracker output (any container of elements with .id, .uv and .xy) of camera `cam`; a rig's
  /// primary camera goes first.
  template <typename Range> void add_frame(int64_t t_cam_ns, const Range &observations, int cam = 0) {
    for (const auto &o : observations)
      add_observation(o.id, t_cam_ns, o.uv, o.xy, cam);
  }

  /// Features whose newest observation is older than t_newest_cam_ns: the tracker lost them in (or before) the
  /// frame at t_newest_cam_ns, so their track is complete and ready for an MSCKF update.
  void lost_features(int64_t t_newest_cam_ns, std::vector<const Feature *> &out) const;
  /// Features with at least one observation older than t_cam_ns (e.g. the oldest clone's stamp + 1 when that
  /// clone is about to leave the window).
  void features_older_than(int64_t t_cam_ns, std::vector<const Feature *> &out) const;
  /// Features with an observation stamped exactly t_cam_ns.
  void features_observed_at(int64_t t_cam_ns, std::vector<const Feature *> &out) const;

  /// Drops every observation older than t_cam_ns; features left without observations are removed.
  /// Remaining observations keep their velocity: it was measured against an image that did exist.
  void remove_observations_older_than(int64_t t_cam_ns);
  /// Drops the observation stamped exactly t_cam_ns from every feature (a marginalised clone that is not the
  /// oldest); features left empty are removed. The next observation keeps its velocity for the same reason.
  void remove_observations_at(int64_t t_cam_ns);
  /// Removes one feature (e.g. after it was used in an update); returns false when it does not exist. Its newest
  /// observation is remembered so that, if the tracker keeps the id, the next observation still gets a velocity:
  /// the image motion is a fact of the tracker, not information the filter has used.
  bool remove(size_t id);
  void clear() {
    features_.clear();
    last_seen_.clear();
    last_seen_more_.clear();
  }

  const Feature *get(size_t id) const;
  size_t size() const { return features_.size(); }
  size_t num_observations() const;

  /// Iteration over all features (unordered; use the queries above when order matters).
  const std::unordered_map<size_t, Feature> &features() const { return features_; }

private:
  size_t obs_capacity_;
  std::unordered_map<size_t, Feature> features_;
  std::unordered_map<size_t, FeatureObservation> last_seen_; ///< newest observation of removed features
  /// The same for the further cameras' tracks: last_seen_more_[id][k - 1] (t_cam_ns < 0: none).
  std::unordered_map<size_t, std::vector<FeatureObservation>> last_seen_more_;
};

} // namespace ovton::core
