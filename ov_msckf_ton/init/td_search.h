#pragma once
// Coarse camera-IMU time offset before the filter starts. The filter's t_d converges from a few tens of ms but, started
// 100-150 ms off, its first updates gate or mis-triangulate nearly every feature and it settles confidently on a wrong
// value (docs/robustness.md). Rotation needs no depth: the images' rotation between consecutive frames (a rotation-only
// fit of KLT bearings, through the known camera-IMU rotation) is compared with the gyro integrated over the same
// interval shifted by each candidate t_d, and the best candidate seeds the filter.
#include "ov_core/cam/camera_calib.h"
#include "ov_core/track/track_klt.h"
#include "ov_core/types/sensor_data.h"
#include "ov_msckf_ton/init/init_options.h"

#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace ovton::core {
struct TrackedStart; // ov_core/track/track_pipeline.h
}

namespace ovton::msckf {

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
/// tracked, `tracked` (if given) receives those tracks and the tracker, for a filter with `track` to go on from. The
/// images are tracked with `track` (LK starting points from `rotation_prior` when given and track.gyro_prior).
TdSearchResult search_td(const std::vector<ovton::core::ImageEntry> &images,
                         const std::vector<ovton::core::ImuData> &imu, const ovton::core::CameraCalib &cam,
                         double prior_td_s, const TdSearchOptions &opt = {},
                         const ovton::core::TrackKLTOptions &track = {},
                         std::shared_ptr<const ovton::core::GyroRotationPrior> rotation_prior = nullptr,
                         const TdSearchImageLoader &load = {}, ovton::core::TrackedStart *tracked = nullptr);

} // namespace ovton::msckf
