#pragma once
// A rig's further cameras, as OpenVINS's TrackKLT does in stereo: each camera follows its own tracks over time (KLT
// from its previous image, RANSAC), and picks up the primary camera's features it lacks by KLT from the primary image
// into its own at the same instant, kept only on their epipolar line. Every track carries the primary's feature id, so
// the filter triangulates a landmark across cameras and time.
#include "ov_core/cam/camera_model.h"
#include "ov_core/track/lk_flow.h"
#include "ov_core/track/track_klt.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

namespace ovton::core {

/// Counts of the last frame.
struct SecondaryTrackStats {
  int num_temporal = 0;       ///< tracks carried over from this camera's previous image
  int num_temporal_lost = 0;  ///< LK, RANSAC or the epipolar check dropped them
  int num_matched = 0;        ///< primary features found in this image by left-right matching
  int num_match_rejected = 0; ///< left-right matches off their epipolar line (or LK failed)
  int num_features = 0;       ///< features output
};

/// Distance of the undistorted normalised point x1 (camera 1) from the epipolar line of x0 (camera 0) for the rig's
/// relative pose (p_1 = R_10 p_0 + t_10), in camera 1's normalised units. Infinite when the line is undefined.
double epipolar_distance(const Eigen::Matrix3d &R_10, const Eigen::Vector3d &t_10, const Eigen::Vector2d &x0,
                         const Eigen::Vector2d &x1);

class TrackSecondary {
public:
  TrackSecondary(const TrackSecondary &) = delete;
  TrackSecondary &operator=(const TrackSecondary &) = delete;
  /// `primary` and `camera` with their T_BC (the rig's extrinsics); the options are the primary tracker's (LK window,
  /// pyramid, equalisation, RANSAC threshold). Throws UsageError for cameras at the same place (no baseline).
  TrackSecondary(const CameraModel &primary, const CameraModel &camera, const TrackKLTOptions &opt = {});

  /// This camera's features in `gray` (stamped like the primary's image that `primary` just tracked). A track
  /// ends with the primary's. The reference stays valid until the next call.
  const std::vector<TrackedFeature> &track(int64_t t_cam_ns, const cv::Mat &gray, const TrackKLT &primary);

  const SecondaryTrackStats &last_stats() const { return stats_; }
  const CameraModel &camera() const { return camera_; }

private:
  /// Keeps this camera's track i when its point passes the border and epipolar checks against the primary's `x0`.
  bool on_epipolar_line(const Eigen::Vector2d &x0, const cv::Point2f &uv, Eigen::Vector2d &xy) const;

  CameraModel primary_, camera_;
  TrackKLTOptions opt_;
  LkImagePreparer prep_;
  Eigen::Matrix3d R_10_; ///< primary camera -> this camera
  Eigen::Vector3d t_10_;
  double epi_thresh_ = 0; ///< normalised units

  bool has_prev_ = false;
  int64_t t_prev_ns_ = 0;
  cv::Mat img_;
  LkPyramid lk_prev_, lk_curr_;
  std::vector<size_t> ids_;
  std::vector<cv::Point2f> pts_;
  std::vector<Eigen::Vector2d> xy_;
  std::vector<TrackedFeature> out_;
  SecondaryTrackStats stats_;
};

} // namespace ovton::core
