#pragma once
// VioManager: the filter. It takes IMU readings and images' tracked features in clock order — the estimator facade
// (estimator/estimator.h) decides which readings come before which image — and runs propagation, cloning, the MSCKF
// and SLAM updates and the time-offset model. It owns no threads and no files: states go to a callback, everything
// else it shows to its observers.
#include "ov_core/cam/camera_model.h"
#include "ov_core/track/feature_database.h"
#include "ov_core/track/track_klt.h"
#include "ov_msckf_ton/core/filter_health.h"
#include "ov_msckf_ton/core/filter_observer.h"
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
#include <unordered_map>
#include <vector>

namespace ovton::msckf {

/// Per-frame cost of each stage [ms], accumulated; the benchmark prints means. `networks` is FVON and TPN
/// (training, prediction and FVON's triangulation); it is not part of `update`. `image_load` is what the caller spent
/// decoding images; `tracking` the tracker's time on the filter's thread and `tracking_thread` on a thread of its own
/// (the estimator's tracking stage), which `total` does not contain.
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

/// What a run may know besides its measurements: simulations give the true state (for init.mode groundtruth) and
/// the true offset (for mode oracle).
struct FilterAids {
  std::vector<ovton::core::StateSample> groundtruth; ///< IMU clock, time-ordered
  std::function<double(int64_t t_cam_ns)> td_truth;
};

class VioManager {
public:
  using StateCallback = std::function<void(const ovton::core::StateSample &)>;

  /// `on_state` receives every state the filter hands out (after its health check); `observers` see the updates'
  /// residuals, velocities and each image's features.
  /// `more_cameras`: a rig's further cameras (their features come with each image, process_frame's `more`).
  VioManager(const VioOptions &opt, const ovton::core::CameraCalib &cam, const ovton::core::ImuCalib &imu,
             FilterAids aids = {}, StateCallback on_state = {},
             std::vector<std::shared_ptr<FilterObserver>> observers = {},
             std::vector<ovton::core::CameraCalib> more_cameras = {});

  /// IMU readings, in time order, up to (and one past) each image's IMU-clock time before the image.
  void on_imu(const ovton::core::ImuData &m);
  /// One image's features (tracker output, or a feature-level dataset's points with their undistorted coordinates).
  /// `more[k - 1]`: camera k's features at the same instant (ids of the primary's), for a rig.
  void process_frame(int64_t t_cam_ns, const std::vector<ovton::core::TrackedFeature> &features,
                     const std::vector<std::vector<ovton::core::TrackedFeature>> &more = {});
  /// t_d for an image at t_cam_ns as the next propagation will use it (t_imu = t_cam + t_d): the IMU must reach
  /// t_cam + this + imu_lookahead_ns() before the image.
  double td_for_image_s(int64_t t_cam_ns) const;
  /// How far past an image's IMU-clock time the readings are wanted before it: a centred mean of the body rate at the
  /// image needs half its window (time_offset.jacobian_rate_window_s); a live system pays it as latency.
  int64_t imu_lookahead_ns() const { return ovton::core::s_to_ns(0.5 * opt_.td.jacobian_rate_window_s); }

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
  ovton::core::FeatureDatabase db_;
  Propagator propagator_;
  UpdaterMSCKF updater_;
  UpdaterSLAM slam_;
  std::unique_ptr<State> state_;
  std::deque<ovton::core::ImuData> init_imu_;
  std::unique_ptr<InertialInitializer> inertial_init_; ///< every initialisation but ground truth

  FilterAids aids_;
  StateCallback on_state_;
  std::vector<std::shared_ptr<FilterObserver>> observers_;
  bool want_records_ = false, want_velocities_ = false, want_frames_ = false;
  /// Rows for the observers' velocities of the update's features, with the velocities `used` gives them.
  void show_velocities(const std::vector<const ovton::core::Feature *> &feats, const VelocityProvider &used);
  /// After an image: its state (health-checked) to the callback, its features with their fate to the observers.
  void hand_out(int64_t t_cam_ns, const std::vector<ovton::core::TrackedFeature> &features);
  std::unordered_map<size_t, FrameFeatures::Fate> fate_; ///< this image's updates' verdicts, by feature id

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
