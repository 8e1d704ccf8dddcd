#pragma once
// Options of the initialisers and of the coarse t_d search, nested in the estimator's options tree
// (core/vio_options.h: section `init`, and `time_offset` for the search).

namespace ovton::msckf {

/// Static: from a still start. GroundTruth: from the dataset's truth (simulations). Dynamic: from a moving start
/// (init/dynamic_init.h). Auto: static when the images are still, dynamic when they move (init/inertial_init.h).
enum class InitMode { Static, GroundTruth, Auto, Dynamic };

/// Dynamic initialisation (init/dynamic_init.h): window, features, motion needed, and the quality it must reach. The
/// pixel noise is update.sigma_px's.
struct DynamicInitOptions {
  double window_s = 1.0;         ///< frames used: the newest and those up to this much older
  int min_features = 15;         ///< features tracked through enough of the window
  int max_features = 60;         ///< the longest tracks are used
  int min_observations = 5;      ///< of a feature within the window
  double min_disparity_px = 8.0; ///< median track displacement over the window: less is too little motion
  double huber_px = 2.0;         ///< robust loss: residuals beyond this count linearly
  double sigma_bg_prior = 0.1;   ///< rad/s, prior of the gyro bias around zero (weak: the data decide)
  double sigma_ba_prior = 0.2;   ///< m/s^2, prior of the accelerometer bias around zero
  double max_rms_px = 1.5;       ///< reprojection RMS after the refinement (inliers)
  /// Accept only a well-determined solution: gravity direction and velocity sigmas from the refinement's covariance,
  /// with the accelerometer bias held (what the window determines; the marginals add the b_a prior's share).
  double max_sigma_rollpitch_deg = 0.5;
  double max_sigma_vel = 0.04;
  double sigma_inflation = 2.0; ///< the covariance handed to the filter is this factor (on sigmas) above the fit's
  int max_iterations = 30;
};

struct InitOptions {
  InitMode mode = InitMode::Static;
  double window_s = 1.0;      ///< still IMU data averaged for gravity and gyro bias
  double max_accel_std = 1.0; ///< m/s^2: above this the platform is not still (EuRoC rotors idle: ~0.5)
  double max_gyro_std = 0.1;  ///< rad/s (EuRoC idle: ~0.04)
  /// The filter's prior after a static (or ground-truth) initialisation; yaw and position are also the unobservable
  /// directions' prior of a dynamic one.
  double sigma_rollpitch = 0.01, sigma_yaw = 1e-4, sigma_pos = 1e-4, sigma_vel = 0.01;
  double sigma_bg = 0.005, sigma_ba = 0.05;
  /// auto: the images are still when their median feature motion over still_window_s stays below this [px].
  double still_window_s = 0.3, still_max_disparity_px = 2.0;
  DynamicInitOptions dynamic; ///< YAML keys init.dyn_*
};

/// The coarse t_d search before the filter starts (init/td_search.h), in the modes that estimate t_d: init_s ±
/// range_s is searched with the images' rotation rate against the gyro and the filter starts from what it finds.
/// Started 100+ ms off, the filter diverges (docs/robustness.md); within a few ms it converges in about a second.
struct TdSearchOptions {
  bool enabled = true;     ///< YAML time_offset.search
  double range_s = 0.2;    ///< candidates t_d ∈ prior ± range_s (YAML time_offset.search_range_s)
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
  /// A window that does not start at the first image is tracked with at most this many features (tracker.num_features
  /// if fewer): a rotation fit of bearings needs few, and that tracking is for the search alone.
  int max_features = 100;
};

} // namespace ovton::msckf
