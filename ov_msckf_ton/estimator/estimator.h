#pragma once
// ovton::Estimator: the whole estimator behind one door. A program feeds IMU readings and images (or a feature-level
// recording's points) in the order they arrive and gets states — pose, velocity, biases, t_d ± σ — back through a
// callback or by polling. `ovton run`, `compare`, `benchmark`, the tests and the example in examples/ all drive it the
// same way, so a program that embeds it behaves exactly as the command line does (docs/api.md).
//
// Inside, three stages work on the stream in camera-time order:
//   tracking  — KLT on each image (LK starts from the gyro's rotation when tracker.gyro_prior asks, which waits for
//               the IMU to cover the image);
//   search    — the coarse t_d search (init/td_search.h) holds the tracked images until a window with enough rotation
//               change has passed (at most time_offset's max_start_s + window_s of images), then seeds the filter;
//   filter    — each image waits until the IMU covers t_cam + t_d + the filter's look-ahead, then the readings up to
//               there and the image go to the filter (core/vio_manager.h), and its state comes out.
// With `threaded` the tracking and the filter run on a thread each (tracking overlaps the filter); without, everything
// runs inside the feed calls on the caller's thread. The result is the same byte for byte either way, and whatever the
// interleaving of IMU and images in the caller's feed: the order of work depends on the stamps, never on arrival.
#include "ov_core/cam/camera_calib.h"
#include "ov_core/types/sensor_data.h"
#include "ov_msckf_ton/core/filter_observer.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_msckf_ton/core/vio_options.h"
#include "ov_msckf_ton/init/td_search.h"

#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace ovton {

/// Everything a run is given besides its measurements.
struct EstimatorSetup {
  msckf::VioOptions options;
  core::CameraCalib camera; ///< intrinsics, distortion, T_BC, image size, and the Kalibr time shift as t_d prior
  core::ImuCalib imu;       ///< noise figures (the options may override them)
  /// A rig's further cameras (cam1, ...): their images come with the primary's through feed_images. Empty: monocular.
  std::vector<core::CameraCalib> more_cameras;
  /// Simulations: the true state (for init.mode groundtruth) and the true offset (for mode oracle).
  msckf::FilterAids aids;
  /// Tracking and filter on threads of their own; false: on the caller's thread inside the feed calls.
  bool threaded = true;
  /// Images waiting to be tracked, and tracked images waiting for the filter, before feed_image blocks the caller
  /// (back-pressure). A stage that waits for the IMU never makes the caller wait: it must be able to feed the IMU.
  size_t max_queued_images = 4;
  /// States kept for poll() (the oldest are dropped beyond this).
  size_t max_polled_states = 10000;
  /// What the measurements are, for messages (a dataset folder, a bag, "live").
  std::string source = "the stream";
};

/// Where a run stands.
struct EstimatorStatus {
  enum class Phase {
    Searching,    ///< the coarse t_d search holds the images (the first state comes after it)
    Initialising, ///< the filter waits for the motion (or stillness) its initialisation needs
    Running,      ///< states come out
    Finished,     ///< finish() processed everything
    Stopped       ///< an error stopped it (`stop_reason`), or stop() abandoned the rest
  };
  Phase phase = Phase::Searching;
  bool initialized = false;
  long imu_received = 0, images_received = 0;
  long images_processed = 0; ///< by the filter (before initialisation included)
  long images_skipped = 0;   ///< no IMU reading at or after their IMU-clock time: never processed
  long states_out = 0;
  double td_s = 0, td_sigma_s = 0;                ///< of the newest state (the prior until one comes out)
  std::string init_message;                       ///< what the initialisation did, or waits for
  std::optional<msckf::TdSearchResult> td_search; ///< once the coarse search has decided
  std::string stop_reason;                        ///< why the run stopped (Phase::Stopped)
};

/// What a finished run did (available once finish() or stop() returned).
struct EstimatorReport {
  msckf::VioCounters counters;
  msckf::StageTimes times;
  msckf::UpdateTally acceptance; ///< features used / gated / failed triangulation over the run
  std::string init_message;
  std::optional<msckf::TdSearchResult> td_search;
  long images_skipped = 0;
  /// What the time offset's model did (td/td_model.h): its process noise, TPN's learning, the model check's switch.
  msckf::TdModelStats td_model;
  /// Per image the filter processed: from its feed_image call to its state leaving the filter [ms].
  std::vector<double> latency_ms;
};

class Estimator {
public:
  using StateCallback = std::function<void(const core::StateSample &)>;

  /// Throws UsageError for options or calibration that cannot work. Oracle mode needs setup.aids.td_truth, ground-truth
  /// initialisation setup.aids.groundtruth.
  explicit Estimator(EstimatorSetup setup);
  ~Estimator(); ///< stops the threads (what was not processed is dropped)
  Estimator(const Estimator &) = delete;
  Estimator &operator=(const Estimator &) = delete;

  /// Before the first feed: every state as it leaves the filter (on the filter's thread when threaded).
  void add_state_callback(StateCallback cb);
  /// Before the first feed: residuals, velocities and each image's features (core/filter_observer.h).
  void add_observer(std::shared_ptr<msckf::FilterObserver> observer);

  /// An IMU reading (IMU clock); readings in increasing time order. Throws UsageError otherwise, and rethrows what
  /// stopped the run.
  void feed_imu(const core::ImuData &m);
  /// An image: 8-bit gray of the camera's size, stamped in the camera clock (t_imu = t_cam + t_d); images in increasing
  /// stamp order. The image is shared, not copied: do not write into it afterwards. Throws UsageError for a wrong size
  /// or type or a stamp not after the previous one, and rethrows what stopped the run.
  void feed_image(int64_t t_cam_ns, const cv::Mat &gray);
  /// A rig's images taken at one instant (one camera-clock stamp, the primary's): grays[0] the primary camera's,
  /// grays[k] camera k's of setup.more_cameras (an empty Mat where that camera has no image at this stamp).
  void feed_images(int64_t t_cam_ns, const std::vector<cv::Mat> &grays);
  /// A feature-level recording's image: the points seen (ids, distorted pixels) instead of pixels.
  void feed_features(int64_t t_cam_ns, std::vector<core::PointObservation> observations);

  /// 1 + setup.more_cameras.size().
  size_t camera_count() const;

  /// Moves the states that came out since the last poll to `out` (appended); returns how many.
  size_t poll(std::vector<core::StateSample> &out);
  EstimatorStatus status() const;

  /// The end of the stream: processes what waits (images beyond the IMU are skipped), joins the threads, and rethrows
  /// what stopped the run (EstimatorFailure for a diverged estimate, ...). A stream from which no state came out is
  /// an error too (DataError naming setup.source, with the initialisation's reason): nothing was estimated.
  void finish();
  /// Abandons what waits (an interrupted run): returns once the threads stopped. Does not throw.
  void stop();
  /// Once finish() or stop() returned.
  EstimatorReport report() const;

private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace ovton
