#pragma once
// Coarse camera-IMU time offset before the filter starts. The filter's t_d converges from a few tens of ms but, started
// 100-150 ms off, its first updates gate or mis-triangulate nearly every feature and it settles confidently on a wrong
// value (docs/robustness.md). Rotation needs no depth: the images' rotation between consecutive frames (a rotation-only
// fit of KLT bearings, through the known camera-IMU rotation) is compared with the gyro integrated over the same
// interval shifted by each candidate t_d, and the best candidate seeds the filter.
#include "ov_core/cam/camera_calib.h"
#include "ov_core/track/track_klt.h"
#include "ov_core/types/sensor_data.h"

#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace ovton::core {
struct TrackedStart; // ov_core/track/track_pipeline.h
}

namespace ovton::msckf {

struct TdSearchOptions {
  double range_s = 0.2;    ///< candidates t_d ∈ prior ± range_s
  double step_s = 0.001;   ///< grid step of the first pass (refined to 0.1 ms around the best)
  double window_s = 8.0;   ///< seconds of images used
  double max_start_s = 60; ///< how far into the recording a window with enough rotation is looked for
  /// RMS angular acceleration [rad/s^2] a window needs: the cost's curvature in t_d grows with it, and a still start
  /// (EuRoC's first seconds) or a constant turn leaves t_d undetermined.
  double min_rms_alpha = 0.5;
  double max_sigma_s = 0.004; ///< a result with a larger standard error is reported but not used
  /// Rate differences are compared after taking away their mean over this long a stretch (gyro bias and the slowly
  /// varying translational flow a rotation fit takes up).
  double highpass_s = 0.5;
  int min_pairs = 40; ///< consecutive image pairs with a rotation fit
  ovton::core::TrackKLTOptions track;
  /// The raw gyro for the tracker's LK starting points (track.gyro_prior); none: LK starts where a point was.
  std::shared_ptr<const ovton::core::GyroRotationPrior> rotation_prior;
  /// A window that does not start at the first image is tracked with at most this many features (track.num_features
  /// if fewer): a rotation fit of bearings needs few, and that tracking is for the search alone. Measured at 100
  /// against 200: the same t_d within 0.3 ms and σ within 0.05 ms on the real cut and renders of V1_03 and MH_03, the
  /// same APE and TPE. A window from the first image is tracked with `track` as it is, as the filter tracks it, so
  /// that the filter can take over its tracks (search_td's `tracked`).
  int max_features = 100;
};

struct TdSearchResult {
  bool found = false;   ///< true when td_s is trustworthy enough to seed the filter
  double prior_s = 0.0; ///< the centre of the search
  double range_s = 0.0; ///< its half width
  double td_s = 0.0;    ///< best candidate (also when not found, if one was computed)
  double sigma_s = 0.0; ///< its standard error: the cost's curvature, or larger for correlated rows
  std::string why;      ///< when not found: why the prior is kept
  int pairs = 0;        ///< image pairs in the fit
  double window_begin_s = 0, window_end_s = 0; ///< seconds after the first image
  double rms_alpha = 0.0;                      ///< rad/s^2 over the window
  /// The window's rotation rate barely changes (rms_alpha below TdSearchOptions::min_rms_alpha): t_d is weakly
  /// observable there, for the filter as for the search (`ovton run` says so beside the final t_d).
  bool weak_excitation = false;
  double seconds = 0.0; ///< wall time of the search
  /// Robust cost per candidate of the grid (prior − range ... prior + range in steps), for plots and diagnosis.
  std::vector<double> cost_profile;
  double residual_sigma = 0.0; ///< rad/s per axis at the best candidate
  /// One line for the run summary, e.g. "t_d 10.2 ± 0.4 ms (search 160 ± 200 ms, images 0.0-8.0 s, 159 pairs, 1.3 s)".
  std::string summary() const;
};

/// Decodes an image for the search (default: ovton::core::load_gray_image with the camera's size).
using TdSearchImageLoader = std::function<cv::Mat(const ovton::core::ImageEntry &)>;

/// Searches t_d over prior_td_s ± opt.range_s. Feature-level entries (ImageEntry::features) are used as given; others
/// are decoded and tracked. Never throws for weak data: `found` is false and `why` says what was missing. Throws
/// DataError (from the loader) for an unreadable image. When the window starts at the first image and all of it was
/// tracked, `tracked` (if given) receives those tracks and the tracker, for a filter with opt.track to go on from.
TdSearchResult search_td(const std::vector<ovton::core::ImageEntry> &images,
                         const std::vector<ovton::core::ImuData> &imu, const ovton::core::CameraCalib &cam,
                         double prior_td_s, const TdSearchOptions &opt = {}, const TdSearchImageLoader &load = {},
                         ovton::core::TrackedStart *tracked = nullptr);

} // namespace ovton::msckf
