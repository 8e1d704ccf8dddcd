#pragma once
// Every option of the estimator, nested per component, with defaults; one YAML loader (one table of keys) that
// prints what it loaded. The YAML file has one section per struct below (time_offset, ton, update, zupt, tracker,
// imu, init); `ovton run` prints the whole tree it uses.
#include "ov_core/track/track_klt.h"
#include "ov_msckf_ton/core/td_mode.h"

#include <iosfwd>
#include <string>

namespace ovton::msckf {

/// Static: from a still start. GroundTruth: from the dataset's truth (simulations). Dynamic: from a moving start
/// (init/dynamic_init.h). Auto: static when the images are still, dynamic when they move (init/inertial_init.h).
enum class InitMode { Static, GroundTruth, Auto, Dynamic };
/// Image-plane velocity of tracked observations: Backward is the paper's eq. 2 (previous observation); Central
/// leaves the observation's own noise out (CentralVelocityProvider; not the paper's SIR).
enum class SirVelocity { Backward, Central };
/// Velocity of a track's first observation in the image-plane modes: None is the paper's eq. 2 (it has none, so a
/// new feature constrains t_d only once that observation has left the window); Next takes the next observation's
/// (NextForFirstVelocityProvider), so new features constrain t_d at once. In fvon/ton it covers the first observations
/// FVON did not predict.
enum class FirstVelocity { None, Next };

/// Time offset t_d (t_imu = t_cam + t_d): its observation is chosen by `mode`, its motion by `process`.
struct TimeOffsetOptions {
  TdMode mode = TdMode::Sr;
  /// How t_d moves between images (td/td_model.h). Auto: tpn/ton -> tpn, drift -> drift, others -> constant.
  TdProcess process = TdProcess::Auto;
  double init_s = 0.0;        ///< initial / fixed (off) value
  double sigma_init_s = 0.01; ///< prior sigma when t_d is estimated
  /// s/sqrt(s): t_d's noise under the random-walk and drift-state models (the paper's drift noise: 0.1 ms/sqrt(s)).
  double random_walk = 1e-4;
  double random_walk_tpn = 2e-4; ///< s/sqrt(s) under TPN: the offset is allowed to move (paper §IV-C)
  /// Drift state [t_d, ṫ_d]: prior sigma of the rate [s/s] (starts at 0) and its random walk [s/s/sqrt(s)].
  double rate_sigma_init = 1e-3;
  double rate_random_walk = 1e-5;
  /// |ṫ_d| bound [s/s] on TPN's J_td: 10x the paper's drift (0.1 ms/s).
  double rate_max = 0.001;
  /// Covariance matching (td/td_noise_adapter.h): the process noise follows the t_d corrections the updates make,
  /// so that σ(t_d) stays honest when the model's prediction is off. Applies to random walk, drift and tpn (a
  /// constant stays constant). Measured in docs/ton.md: TPN's t_d NEES 4.9 -> 1.0 on the worked case.
  bool adaptive_noise = true;
  /// Covariance matching sums the t_d corrections over the last this-many seconds (0: one image per sample). A
  /// prediction that trails the offset corrects it by many small steps of one sign that no single image shows.
  /// Measured in docs/ton.md ("t_d noise over blocks"): on the 40-s protocol cells ton's t_d NEES 2.27 -> 1.23
  /// at 6 s; unchanged on the 20-s Monte-Carlo renders.
  double adaptive_block_s = 6.0;
  /// The body rate in the clone's t_d Jacobian: 0 = the gyro reading at the image time; > 0 = the mean reading over
  /// this window centred on it (the replay then hands over half of it past the image: latency in a live system). A
  /// vibrating IMU otherwise makes t_d look observable on a gentle flight (docs/robustness.md, "Weak excitation"),
  /// and `diagnose` then read the pulled t_d as a 0.4-0.6 deg camera-IMU rotation on clean flights (docs/diagnose.md).
  double jacobian_rate_window_s = 0.1;
  /// Defaults measured in docs/ton.md (the paper's choices, backward / none, are config/paper/): eq. 2's
  /// backward difference shares the observation's own noise with its residual and biases t̂_d (errors in variables;
  /// TPN then learns and amplifies the bias), and without a first velocity the image-plane modes diverge on a fast
  /// start.
  SirVelocity sir_velocity = SirVelocity::Central;
  FirstVelocity first_velocity = FirstVelocity::Next;
  /// Image-plane modes: take the errors-in-variables bias of the tracked velocities out of each update, scaled by
  /// this (UpdaterMSCKFOptions::td_velocity_debias: 1 for independent pixel errors of the declared σ, as the
  /// feature-level simulations have; KLT's correlated errors make the bias ~0.03 of that, so 0, off, for images).
  /// Measured in docs/ton.md ("Errors in variables"); not in the paper.
  double velocity_debias = 0.0;
  /// TPN: an older clone's image-plane rows use the t_d of its own image, t̂_d − rate·age with TPN's rate, instead of
  /// one t_d for the whole window (State::td_offset_at). On in config/sim with clone_trend_tau_s 10. Other processes
  /// ignore it, as they do random_walk_tpn. Tried in docs/ton.md ("Where the remaining lag comes from").
  bool clone_trend = false;
  /// clone_trend's rate: TPN's, averaged over this time constant (0: the last one, which feeds back on itself).
  double clone_trend_tau_s = 10.0;
  /// Before the filter starts, in the modes that estimate t_d: search init_s ± search_range_s with the images' rotation
  /// rate against the gyro (init/td_search.h) and start from what it finds. Started 100+ ms off, the filter diverges
  /// (docs/robustness.md); within a few ms it converges in about a second.
  bool search = true;
  double search_range_s = 0.2;
};

/// The paper's networks (Table I), trained online. Epochs are per training call, i.e. per frame; lower them to
/// trade accuracy for per-frame cost.
struct TonOptions {
  int fvon_max_labels = 40;    ///< labels per FVON training call (ITS pairs / F2F points)
  int fvon_min_f2f_labels = 5; ///< F2F predicts for a frame only with this many labelled features in it
  /// A prediction for a first observation enters the update only if it agrees with the track's next measured
  /// velocity within this (px/s; 0 = no check). 80 px/s is ~3σ of a 1 px backward difference at 20 Hz.
  double fvon_gate_px_s = 80.0;
  int its_epochs = 1000;            ///< ITS-FVON epochs per call (Table I)
  int f2f_epochs = 1500;            ///< F2F-FVON epochs per call (Table I)
  int tpn_epochs = 1000;            ///< TPN epochs per frame (Table I)
  int tpn_min_labels = 5;           ///< TPN drives t_d only once its buffer holds this many estimates
  double tpn_start_sigma_s = 0.001; ///< TPN learns from t̂_d only once its σ is below this (past convergence)
  /// Images per TPN label: each label is the mean of t̂_d over this many images, and the propagation moves t_d at
  /// (t_d^TPN − last label) / the labels' spacing. 1 is the paper (a label per image). Why 10: per image, the
  /// filter's estimate jitters by more than a drift moves it, and the LSTM then learns the jitter's mean reversion,
  /// not the trend — on the worked case's +0.5 ms/s drift TPN drove t_d at −0.3 to −0.7 ms/s and the noise adapter
  /// made up for it (docs/ton.md, "TPN's labels"; protocol t_d RMSE −27 to −32 % with 10).
  int tpn_label_images = 10;
  /// Beyond the paper (docs/ton.md): ITS and TPN learn the change from their last input (a skip connection
  /// around the same LSTM), F2F sees the 3D point as (X/Z, Y/Z, 1/Z). All false in config/paper/.
  bool its_residual = true;
  bool tpn_residual = true;
  bool f2f_inverse_depth = true;
  /// Plateau stop of the online training (ton/trainer.h): every this many epochs, stop when the loss fell by less
  /// than plateau_rel of itself. 0 = the paper's rule only (epoch limit or loss threshold).
  int plateau_epochs = 20;
  double plateau_rel = 0.01;
  /// FVON's per-call epoch cap after its first `fvon_warmup_trainings` trainings (ton/trainer.h, TrainOptions::
  /// for_call; TPN keeps its cap: it trains once per label, not per frame). 0 = its_epochs / f2f_epochs throughout
  /// (the paper). Measured in docs/ton.md ("Cost").
  int fvon_warmup_trainings = 100;
  int fvon_maintenance_epochs = 200;
};

struct UpdateOptions {
  /// Measurement Jacobians at each clone's first estimate (OpenVINS' FEJ). Measured both ways (docs/results.md):
  /// with it orientation stays consistent, without it APE was lower on two of three simulations but yaw
  /// over-confident.
  bool measurement_fej = true;
  int max_clones = 20;           ///< 1 s at 20 Hz: MSCKF-only accuracy and consistency improve markedly over 11
  int min_track_length = 3;      ///< observations (at clones) a feature needs to enter an MSCKF update
  double min_parallax_deg = 0.2; ///< triangulation: features with less parallax over their track are not used
  double sigma_px = 1.0;         ///< pixel noise of a KLT observation
  double chi2_multiplier = 1.0;  ///< scales the 95% chi-square gate
  int max_features = 80;         ///< per update
  /// Correlation of a track's pixel errors between consecutive observations (AR(1)); 0: independent. KLT's errors
  /// are not: 0.77 between frames on a rendered V1_02 flight (docs/consistency_images.md), which the 1 px weight
  /// covers.
  double track_correlation = 0.0;
  /// The AR(1) ρ of those errors in the covariance only: the gain keeps the independent sigma_px weight, the
  /// covariance is that weight's error under correlated errors (UpdaterMSCKFOptions::covariance_track_correlation).
  double covariance_track_correlation = 0.0;
};

/// SLAM features (update/updater_slam.h): features tracked through the whole window become landmarks in the state.
struct SlamOptions {
  int max_features = 0;        ///< landmarks in the state at most (0: MSCKF only; OpenVINS' default is 50)
  int max_init_per_frame = 10; ///< delayed initialisations per image at most
  double chi2_multiplier = 1.0;
  double sigma_px = 0.0; ///< pixel noise of a landmark observation; 0 = update.sigma_px
  /// Correlation of a landmark's pixel errors between consecutive images (AR(1)); 0: independent. A landmark is
  /// re-observed at every image, so a slowly wandering track error is otherwise counted again at each.
  double track_correlation = 0.0;
  /// Pixel noise of a landmark's re-observations in the covariance only (UpdaterSlamOptions::covariance_sigma_px);
  /// 0: off.
  double covariance_sigma_px = 0.0;
  /// Image-plane modes: a landmark's t_d row uses the image velocity its state predicts, not the tracked backward
  /// difference that shares the row's pixel noise (UpdaterSlamOptions::state_velocity; docs/ton.md).
  bool state_velocity = true;
};

/// Online calibration (OpenVINS-style): each estimated quantity becomes a state variable with the prior sigma given
/// here, starting from the dataset's calibration. Off by default: each costs observability time and, where the
/// calibration is right, a little accuracy (measured in docs/results.md).
struct CalibrationOptions {
  bool extrinsics = false;      ///< camera–IMU rotation and translation
  double sigma_ext_rot = 0.01;  ///< [rad]
  double sigma_ext_pos = 0.01;  ///< [m]
  bool intrinsics = false;      ///< focal lengths, principal point, distortion
  double sigma_focal_px = 2.0;  ///< fu, fv [px]
  double sigma_center_px = 2.0; ///< cu, cv [px]
  double sigma_distortion = 0.005;
  bool readout = false;   ///< rolling-shutter readout time
  double readout_s = 0.0; ///< known (or initial) readout [s]: row v is seen at t + t_d + (v/H − ½)·t_r
  double sigma_readout_s = 0.01;
  /// The readout's row shift V·ρ·t_r with the image velocity the state predicts (true) or the track's measured one
  /// (false, as before session 29): UpdaterMSCKFOptions::readout_state_velocity.
  bool readout_state_velocity = true;
  bool imu_intrinsics = false; ///< gyro and accelerometer scale and misalignment (lower-triangular D_w, D_a)
  double sigma_imu_intrinsics = 0.01;
};

/// Zero-velocity update: when the features do not move on the image the platform is taken as still, the state
/// gets a v = 0 measurement instead of a clone (no parallax would make every MSCKF feature untriangulable).
struct ZuptOptions {
  bool enabled = true;
  double max_disparity_px = 0.5; ///< median feature motion since the previous frame below this = still
  double sigma_v = 0.02;         ///< m/s; covers the rotor vibration of a MAV standing on the ground
};

/// IMU noise comes from the dataset's sensor.yaml, multiplied by noise_multiplier (inflation is common practice).
/// A value > 0 below replaces the folder's (Kalibr names): a datasheet understates a real IMU's noise, and
/// the measured values belong to the sensor, not to each recording (config/euroc_mav: the ADIS16448 as measured).
struct ImuOptions {
  double noise_multiplier = 1.0;
  double gravity_mag = 9.81;
  double gyroscope_noise_density = 0.0, gyroscope_random_walk = 0.0;
  double accelerometer_noise_density = 0.0, accelerometer_random_walk = 0.0;
};

struct InitOptions {
  InitMode mode = InitMode::Static;
  double window_s = 1.0;      ///< still IMU data averaged for gravity and gyro bias
  double max_accel_std = 1.0; ///< m/s^2: above this the platform is not still (EuRoC rotors idle: ~0.5)
  double max_gyro_std = 0.1;  ///< rad/s (EuRoC idle: ~0.04)
  double sigma_rollpitch = 0.01, sigma_yaw = 1e-4, sigma_pos = 1e-4, sigma_vel = 0.01;
  double sigma_bg = 0.005, sigma_ba = 0.05;
  /// auto: the images are still when their median feature motion over still_window_s stays below this [px].
  double still_window_s = 0.3, still_max_disparity_px = 2.0;
  /// Dynamic initialisation (init/dynamic_init.h): window, features, motion needed, and the quality it must reach.
  double dyn_window_s = 1.0;
  int dyn_min_features = 15, dyn_max_features = 60, dyn_min_observations = 5;
  double dyn_min_disparity_px = 8.0, dyn_max_rms_px = 1.5;
  double dyn_max_sigma_rollpitch_deg = 0.5, dyn_max_sigma_vel = 0.04;
  double dyn_sigma_inflation = 2.0; ///< the covariance handed to the filter, in sigmas above the fit's
};

/// Stop the run (ovton::core::EstimatorFailure) when the estimate has evidently diverged (core/filter_health.h). Off
/// only to watch a divergence to its end; a non-finite state stops the run either way.
struct HealthOptions {
  bool enabled = true;
};

struct VioOptions {
  TimeOffsetOptions td;
  TonOptions ton;
  UpdateOptions update;
  SlamOptions slam;
  CalibrationOptions calibration;
  ZuptOptions zupt;
  ovton::core::TrackKLTOptions track; ///< YAML section `tracker`
  ImuOptions imu;
  InitOptions init;
  HealthOptions health;
  std::string source; ///< file the options came from, "" for defaults
};

/// Sets the mode and, unless Auto, the process of a `MODE[+PROCESS]` spec.
void apply_mode_spec(const ModeSpec &spec, VioOptions &o);

/// Loads a VioOptions YAML: sections as the structs above, keys as their members. Unknown or duplicate keys, values
/// of the wrong kind and out-of-range values are errors naming the file and line. When `print` is set, writes every
/// loaded value there.
VioOptions load_vio_options(const std::string &file, std::ostream *print = nullptr);
void print_vio_options(const VioOptions &o, std::ostream &os);
/// Range checks shared by the loader and programmatic callers; throws ovton::core::UsageError naming the key.
void validate_vio_options(const VioOptions &o);

std::string to_string(InitMode m);
InitMode parse_init_mode(const std::string &s); ///< static | groundtruth | auto | dynamic; throws UsageError

} // namespace ovton::msckf
