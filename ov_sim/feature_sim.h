#pragma once
// Feature-level simulation: landmarks on the scene's faces, observed with pixel noise through the camera
// model, organised into tracks that start and end the way a KLT front end's do. For filter tests that must
// not depend on the tracker.
#include "ov_core/cam/camera_model.h"
#include "ov_sim/frame_pose.h"
#include "ov_sim/random.h"
#include "ov_sim/scene.h"
#include <cstdint>
#include <vector>

namespace ovton::sim {

struct FeatureSimOptions {
  int max_tracks = 200;             ///< live tracks, as a tracker configured for 200 points
  int grid_cols = 8, grid_rows = 5; ///< new tracks are spawned in cells holding fewer than their share
  double pixel_noise = 1.0;         ///< sigma of the observation noise [px]
  double mean_track_length = 30.0;  ///< frames; tracks also end when the point leaves view or is occluded
  double border_px = 5.0;           ///< points closer to the image border are lost
  double landmarks_per_m2 = 20.0;   ///< landmark density on every visible face
  double min_depth_m = 0.2;
  uint64_t seed = 0;
};

struct FeatureObservation {
  int64_t t_cam_ns = 0;
  uint64_t feature_id = 0;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero(); ///< distorted pixel, noise included
};

class FeatureSimulator {
public:
  FeatureSimulator(const ovton::core::CameraModel &cam, const Scene &scene, const FeatureSimOptions &opt);

  /// Observations of one frame: the camera at (R_WC, p_WC) at its true instant, stamped t_cam_ns.
  std::vector<FeatureObservation> step(const Eigen::Matrix3d &R_WC, const Eigen::Vector3d &p_WC, int64_t t_cam_ns);
  /// Same with a rolling shutter when pose.at_row is set: a landmark is seen from the pose of the row it lands in,
  /// found by fixed-point iteration on the row (it converges by the factor image velocity × row time per step).
  std::vector<FeatureObservation> step(const FramePose &pose, int64_t t_cam_ns);

  const std::vector<Eigen::Vector3d> &landmarks() const { return landmarks_; }
  /// Landmark observed by a feature id (ids are never reused; a re-detected landmark gets a new id).
  size_t landmark_of(uint64_t feature_id) const { return track_landmark_.at(feature_id); }

private:
  bool visible(size_t lm, const FramePose &pose, Eigen::Vector2d &uv) const;
  const ovton::core::CameraModel &cam_;
  const Scene &scene_;
  FeatureSimOptions opt_;
  Rng rng_;
  std::vector<Eigen::Vector3d> landmarks_;
  std::vector<int64_t> live_;          ///< landmark -> live feature id, -1 if untracked
  std::vector<size_t> track_landmark_; ///< feature id -> landmark
};

} // namespace ovton::sim
