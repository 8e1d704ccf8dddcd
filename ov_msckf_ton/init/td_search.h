#pragma once
// Coarse camera-IMU time offset before the filter starts. The filter's t_d converges from a few tens of ms but, started
// 100-150 ms off, its first updates gate or mis-triangulate nearly every feature and it settles confidently on a wrong
// value (docs/robustness.md). Rotation needs no depth: the images' rotation between consecutive frames (a rotation-only
// fit of KLT bearings, through the known camera-IMU rotation) is compared with the gyro integrated over the same
// interval shifted by each candidate t_d, and the best candidate seeds the filter.
#include "ov_core/cam/camera_calib.h"
#include "ov_core/track/track_klt.h"
#include "ov_core/types/imu_buffer.h"
#include "ov_core/types/sensor_data.h"
#include "ov_msckf_ton/init/init_options.h"
#include "ov_msckf_ton/init/td_search_fit.h"

#include <deque>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

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
  /// When weak_excitation: the caution `ovton run` and `ovton compare` print beside the result ("" otherwise).
  std::string caution() const;
};

/// The search on a stream: IMU readings and images' features arrive in time order, and the search decides once a
/// window of images whose rotation changes enough is complete — the first of the windows that start 0, 1, 2, ... s
/// after the first image (at most opt.max_start_s in), or the best of them when none does — or when the stream ends.
/// Which window qualifies depends on the gyro alone, so a window is judged as soon as its last image has passed and
/// the IMU covers it; its images' features were kept meanwhile. A driver (the estimator's tracking stage, or
/// search_td below) asks before handing on each image whether the search must decide first:
///
///     while (!s.done() && s.must_decide_before(t_cam_ns)) { wait until s.imu_needed_ns() is covered; s.decide(false);
///     } if (!s.done()) s.add_frame(t_cam_ns, bearings);
///
/// and calls decide(true) at the end of the stream until done().
class TdSearch {
public:
  /// A unit bearing of a feature in the camera frame, by feature id.
  using Bearings = std::vector<std::pair<size_t, Eigen::Vector3d>>;

  TdSearch(const ovton::core::CameraCalib &cam, double prior_td_s, const TdSearchOptions &opt);

  /// IMU readings in time order. What lies more than a minute before the first image (IMU clock) is dropped.
  void add_imu(const ovton::core::ImuData &m);
  /// The features of the next image (camera clock, after every image added so far); ignored once done().
  void add_frame(int64_t t_cam_ns, Bearings bearings);

  /// Whether the current window must be judged before an image at t_cam_ns is added (it lies past the window's end).
  bool must_decide_before(int64_t t_cam_ns) const;
  /// The IMU-clock time the readings must pass before decide(false): the window's last image, shifted by the largest
  /// candidate offset, plus the margin the fit's filters look beyond it.
  int64_t imu_needed_ns() const;
  /// Judges the current window; `end_of_stream`: no image follows. Returns done().
  bool decide(bool end_of_stream);

  bool done() const { return done_; }
  /// The outcome; meaningful once done().
  const TdSearchResult &result() const { return res_; }

private:
  struct Frame {
    int64_t t_cam_ns;
    Bearings bearings;
  };
  /// Camera seconds after the first image.
  double rel_s(int64_t t_cam_ns) const { return ovton::core::ns_to_s(t_cam_ns - t0_ns_); }
  /// Kept frames [b, e) of the window starting start_s after the first image (e: the first at or after its end).
  std::pair<size_t, size_t> window(double start_s) const;
  /// The images' rotation rates between consecutive kept frames [b, e).
  std::vector<PairRate> pair_rates(size_t b, size_t e) const;
  void conclude(bool end_of_stream);

  ovton::core::CameraCalib cam_;
  double prior_s_;
  TdSearchOptions opt_;
  ovton::core::ImuBuffer imu_;
  int64_t t0_ns_ = 0;        ///< the first image's stamp
  size_t frames_seen_ = 0;   ///< images added in all
  std::deque<Frame> frames_; ///< from the current window's start on
  double start_s_ = 0;       ///< the current candidate window's start
  /// The window whose rotation changed most so far: its rms angular acceleration, first and last image [s], images.
  double best_rms_ = -1, best_begin_s_ = 0, best_end_s_ = 0;
  size_t best_images_ = 0;
  double compute_s_ = 0; ///< time spent judging
  bool done_ = false;
  TdSearchResult res_;
};

/// Decodes an image for the search (default: ovton::core::load_gray_image with the camera's size).
using TdSearchImageLoader = std::function<cv::Mat(const ovton::core::ImageEntry &)>;

/// The search over a whole recording (`ovton info --td-search`, tests): the images are tracked from the first with
/// `track` (LK starting points from `rotation_prior` when given and track.gyro_prior) until the search decides, as the
/// estimator's tracking stage tracks them; feature-level entries (ImageEntry::features) are used as given. Never throws
/// for weak data: `found` is false and `why` says what was missing. Throws DataError (from the loader) for an
/// unreadable image.
TdSearchResult search_td(const std::vector<ovton::core::ImageEntry> &images,
                         const std::vector<ovton::core::ImuData> &imu, const ovton::core::CameraCalib &cam,
                         double prior_td_s, const TdSearchOptions &opt = {},
                         const ovton::core::TrackKLTOptions &track = {},
                         std::shared_ptr<const ovton::core::GyroRotationPrior> rotation_prior = nullptr,
                         const TdSearchImageLoader &load = {});

/// A tracked image's features as the search's bearings.
TdSearch::Bearings bearings_of(const std::vector<ovton::core::TrackedFeature> &features);

} // namespace ovton::msckf
