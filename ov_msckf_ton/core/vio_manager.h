#pragma once
// VioManager: takes IMU readings and images in clock order (it is a ReplayConsumer), and runs front end,
// propagation, cloning, MSCKF update and the time-offset strategy. It owns no files: output goes to callbacks.
#include "ov_core/cam/camera_model.h"
#include "ov_core/io/replay.h"
#include "ov_core/io/velocity_log.h"
#include "ov_core/track/feature_database.h"
#include "ov_core/track/track_klt.h"
#include "ov_msckf_ton/core/filter_health.h"
#include "ov_msckf_ton/core/vio_options.h"
#include "ov_msckf_ton/init/inertial_init.h"
#include "ov_msckf_ton/state/propagator.h"
#include "ov_msckf_ton/state/state.h"
#include "ov_msckf_ton/td/td_model.h"
#include "ov_msckf_ton/td/td_models.h"
#include "ov_msckf_ton/ton/fvon_provider.h"
#include "ov_msckf_ton/ton/tpn_driver.h"
#include "ov_msckf_ton/update/residual_log.h"
#include "ov_msckf_ton/update/updater_msckf.h"
#include "ov_msckf_ton/update/updater_slam.h"

#include <array>
#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

namespace ovton::core {
struct TrackedFrame; // ov_core/track/track_pipeline.h
}

namespace ovton::msckf {

/// Per-frame cost of each stage [ms], accumulated; the benchmark prints means. `networks` is FVON and TPN
/// (training, prediction and FVON's triangulation); it is not part of `update`. With a frame source that tracks on
/// a thread of its own, `image_load` is the filter's wait for a tracked image and `tracking` stays 0; the tracking
/// thread's own time is `tracking_thread`, which `total` does not contain. Images whose tracks were given (the coarse
/// t_d search's) cost neither.
struct StageTimes {
  long frames = 0;
  double image_load = 0, tracking = 0, propagation = 0, update = 0, networks = 0, total = 0;
  double tracking_thread = 0;
};

struct VioCounters {
  long images = 0, images_before_init = 0, updates = 0, features_used = 0, features_gated = 0, features_rejected = 0;
  long td_rows = 0; ///< observations whose residual carried a t_d column
  /// td_rows split by where the velocity came from (index: VelocitySource; 0 stays 0). FVON's job is to add rows
  /// from ITS/F2F: a new feature's first observation has no tracked velocity, and without one none of its rows
  /// may carry t_d (updater_msckf.cpp).
  std::array<long, kNumVelocitySources> td_rows_by_source{};
  long td_features = 0;                                        ///< used features whose rows carried t_d
  long zupts = 0;                                              ///< frames handled by a zero-velocity update
  long slam_initialised = 0, slam_updates = 0, slam_gated = 0; ///< SLAM landmarks initialised, observations used
};

class VioManager : public ovton::core::ReplayConsumer {
public:
  using StateCallback = std::function<void(const ovton::core::StateSample &)>;

  VioManager(const VioOptions &opt, const ovton::core::CameraCalib &cam, const ovton::core::ImuCalib &imu);

  /// Oracle mode: the true offset at a camera stamp (needed before the first image).
  void set_td_oracle(std::function<double(int64_t t_cam_ns)> f) { td_oracle_ = std::move(f); }
  /// Ground-truth initialisation: the true state at an IMU-clock time.
  void set_groundtruth(std::vector<ovton::core::StateSample> gt) { gt_ = std::move(gt); }
  void set_state_callback(StateCallback cb) { on_state_ = std::move(cb); }
  void set_residual_log(ResidualLogWriter *log) { log_ = log; }
  /// Per observation of every feature an update uses, each rule's and network's image velocity (for
  /// `ovton velocities`). In modes fvon/ton it makes FVON predict with both networks (on a copy; same trajectory).
  void set_velocity_log(ovton::core::VelocityLogWriter *log);
  /// Where on_image gets its decoded image (e.g. an ovton::core::ImagePrefetcher); default ovton::core::load_image (the
  /// file, or the bag message). An empty image is reported as unreadable, naming the file.
  using ImageSource = std::function<cv::Mat(const ovton::core::ImageEntry &)>;
  void set_image_source(ImageSource src) { image_source_ = std::move(src); }
  /// The raw gyro for the tracker's LK starting points (tracker.gyro_prior), when this manager tracks the images.
  void set_rotation_prior(std::shared_ptr<const ovton::core::GyroRotationPrior> prior) {
    tracker_.set_rotation_prior(std::move(prior));
  }
  /// Where on_image gets an image's tracked features when they are tracked elsewhere (an ovton::core::TrackPipeline
  /// with this manager's tracker options and camera): set, it replaces the image source and the manager's own tracker.
  using FrameSource = std::function<ovton::core::TrackedFrame(const ovton::core::ImageEntry &)>;
  void set_frame_source(FrameSource src) { frame_source_ = std::move(src); }

  void on_imu(const ovton::core::ImuData &m) override;
  /// Loads the image named in the entry (grayscale, from the image source), then processes it.
  void on_image(const ovton::core::ImageEntry &e) override;
  double td_for_image_s(int64_t t_cam_ns) const override;
  int64_t imu_lookahead_ns() const override { return ovton::core::s_to_ns(0.5 * opt_.td.jacobian_rate_window_s); }

  /// Processes an already decoded image (benchmarks, tests, prefetching callers).
  void process_image(int64_t t_cam_ns, const cv::Mat &gray);
  /// Processes one frame of a feature-level dataset (no tracker: the observations are given).
  void process_features(int64_t t_cam_ns, const std::vector<ovton::core::PointObservation> &obs);

  bool initialized() const { return initialized_; }
  const State &state() const { return *state_; }
  const StageTimes &times() const { return times_; }
  const VioCounters &counters() const { return counters_; }
  const VioOptions &options() const { return opt_; }
  const std::string &init_message() const { return init_msg_; }
  /// FVON diagnostics (modes fvon, ton), nullptr otherwise.
  const FvonVelocityProvider *fvon() const { return fvon_.get(); }
  /// How t_d moves between images (td/td_model.h).
  const TdModel &td_model() const { return *td_model_; }
  /// TPN driver (process tpn: modes tpn, ton), nullptr otherwise.
  const TpnDriver *tpn() const;
  /// Update acceptance so far; every state handed out has passed its check (filter_health.h).
  const FilterHealth &health() const { return health_; }

private:
  void process_frame(int64_t t_cam_ns, std::chrono::steady_clock::time_point t_start);
  bool try_initialize(int64_t t_cam_ns);
  /// The calibration variables the options ask for, with their priors (at initialisation, before any clone).
  void add_calibration_variables();
  /// The features the tracker has in this image, for the initialiser (it keeps its own window of them).
  InitFrame init_frame(int64_t t_cam_ns, int64_t t_imu_ns) const;
  void update_and_marginalize(int64_t t_cam_ns);
  /// The velocities every update of this image uses: the configured rule for tracked observations, FVON's
  /// predictions (fvon/ton) and the next observation's for first ones (first_velocity next).
  const VelocityProvider &prepare_velocities(const std::vector<const ovton::core::Feature *> &feats,
                                             std::optional<NextForFirstVelocityProvider> &with_first);
  void msckf_update(const std::vector<const ovton::core::Feature *> &feats, const VelocityProvider &velocities);
  /// SLAM landmarks: update with this image, initialise `init` from the window, marginalise the lost ones.
  void slam_update(int64_t t_cam_ns, const std::vector<const ovton::core::Feature *> &init,
                   const VelocityProvider &velocities);
  /// Median feature motion since the previous frame is below the ZUPT threshold.
  bool is_still(int64_t t_cam_ns) const;
  /// Propagates the IMU state and t_d (through its model) to the image's IMU-clock time.
  void propagate_to_image(int64_t t_cam_ns);
  /// An EKF update wrapped so that t_d's model sees the correction it made.
  template <typename UpdateFn> void td_tracked_update(UpdateFn &&fn);
  /// After an image: the t_d model learns (TPN), the networks' time is counted.
  void finish_image(int64_t t_cam_ns);
  ovton::core::StateSample snapshot() const;

  VioOptions opt_;
  ovton::core::CameraModel camera_;
  ovton::core::TrackKLT tracker_;
  ovton::core::FeatureDatabase db_;
  Propagator propagator_;
  UpdaterMSCKF updater_;
  UpdaterSLAM slam_;
  std::unique_ptr<State> state_;
  std::deque<ovton::core::ImuData> init_imu_;
  std::unique_ptr<InertialInitializer> inertial_init_; ///< every initialisation but ground truth

  std::function<double(int64_t)> td_oracle_;
  std::vector<ovton::core::StateSample> gt_;
  StateCallback on_state_;
  ResidualLogWriter *log_ = nullptr;
  ovton::core::VelocityLogWriter *velocity_log_ = nullptr;
  /// Rows of the velocity log for the update's features, with the velocities `used` gives them.
  void log_velocities(const std::vector<const ovton::core::Feature *> &feats, const VelocityProvider &used);
  ImageSource image_source_;
  FrameSource frame_source_;

  bool initialized_ = false;
  std::string init_msg_;
  VelocityProvider tracked_velocities_;        ///< constant-speed velocities of the front end (paper eq. 2)
  CentralVelocityProvider central_velocities_; ///< option sir_velocity: central
  std::unique_ptr<FvonVelocityProvider> fvon_; ///< modes fvon, ton
  std::unique_ptr<TdModel> td_model_;
  int64_t last_image_ns_ = -1; ///< camera stamp of the previous processed image
  StageTimes times_;
  VioCounters counters_;
  FilterHealth health_;
};

} // namespace ovton::msckf
