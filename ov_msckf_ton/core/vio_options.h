#pragma once
// Every option of the estimator in one tree: each component's own options struct nested in the section that
// configures it, so that a key has one default, in one place, and no component receives a copy. One YAML loader (one
// table of keys, vio_options.cpp) reads it and prints what it loaded. The YAML file has one section per struct below
// (time_offset, ton, update, slam, calibration, zupt, tracker, imu, init, health); a few keys sit in the section a user
// looks for them in rather than in the struct that holds them (the table says where). `ovton run` prints the whole
// tree it uses.
#include "ov_core/track/track_klt.h"
#include "ov_msckf_ton/core/td_mode.h"
#include "ov_msckf_ton/init/init_options.h"
#include "ov_msckf_ton/ton/ton_options.h"
#include "ov_msckf_ton/update/update_options.h"

#include <iosfwd>
#include <string>

namespace ovton::msckf {

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
  /// Covariance matching (td/td_noise_adapter.h): the process noise follows the t_d corrections the updates make,
  /// so that σ(t_d) stays honest when the model's prediction is off. Applies to random walk, drift and tpn (a
  /// constant stays constant). docs/ton.md measures what it does for TPN's t_d NEES.
  bool adaptive_noise = true;
  /// Covariance matching sums the t_d corrections over the last this-many seconds (0: one image per sample). A
  /// prediction that trails the offset corrects it by many small steps of one sign that no single image shows.
  /// docs/ton.md, "t_d noise over blocks", has what it does on the protocol cells and the Monte-Carlo renders.
  double adaptive_block_s = 6.0;
  /// The model check (td/td_model_check.h): t_d goes to the drift state when its corrections over two stretches of
  /// model_check_window_s in a row each sum to more than model_check_z sigmas of what the updates allowed, with the
  /// same sign and more than model_check_min_step_s. Not for the drift state itself, nor where t_d is not estimated.
  /// Why these values (measured in docs/robustness.md, "The model check"): shorter stretches take a filter converging
  /// from far off (search off) for a trend; a higher z misses the real cut's fast drifts in the time it has; the floor
  /// keeps a long flight's tight sigma from calling a drift of no consequence a trend.
  bool model_check = true;
  double model_check_window_s = 1.0;
  double model_check_z = 2.0;
  double model_check_min_step_s = 0.1e-3;
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
  /// TPN: an older clone's image-plane rows use the t_d of its own image, t̂_d − rate·age with TPN's rate, instead of
  /// one t_d for the whole window (State::td_offset_at). On in config/sim with clone_trend_tau_s 10. Other processes
  /// ignore it, as they do random_walk_tpn. Tried in docs/ton.md ("Where the remaining lag comes from").
  bool clone_trend = false;
  /// clone_trend's rate: TPN's, averaged over this time constant (0: the last one, which feeds back on itself).
  double clone_trend_tau_s = 10.0;
  /// A rig's further cameras each get an offset of their own (State::CameraTdState: camera k's t_d is t_d + Δ_k)
  /// instead of sharing cam0's: for cameras whose images the driver pairs under one stamp although they are not
  /// triggered together. Only in the modes that estimate t_d. Δ_k follows a random walk, and per_camera_rate gives
  /// it a rate of its own; cam0's model (constant, random walk, drift, TPN) stays cam0's, which camera k's t_d
  /// inherits. docs/stereo.md.
  bool per_camera = false;
  double per_camera_sigma_init_s = 0.01; ///< prior sigma of Δ_k (which starts at 0: camera k at cam0's t_d)
  double per_camera_random_walk = 1e-4;  ///< s/sqrt(s): Δ_k's noise
  /// Δ_k's rate Δ̇_k in the state (prior rate_sigma_init, random walk rate_random_walk, as t_d's drift state): a
  /// camera whose clock drifts against cam0's, followed without the random walk's lag.
  bool per_camera_rate = false;
  TdSearchOptions search; ///< the coarse search before the filter starts (init/init_options.h)
};

/// The paper's networks (Table I), trained online: FVON's provider and TPN's driver with their networks' options
/// (ton/ton_options.h). Epochs are per training call, i.e. per frame; lower them to trade accuracy for per-frame cost.
struct TonOptions {
  FvonProviderOptions fvon;
  TpnDriverOptions tpn;             ///< its td_rate_max is YAML time_offset.rate_max
  double tpn_start_sigma_s = 0.001; ///< TPN learns from t̂_d only once its σ is below this (past convergence)
  /// Images per TPN label: each label is the mean of t̂_d over this many images, and the propagation moves t_d at
  /// (t_d^TPN − last label) / the labels' spacing. 1 is the paper (a label per image). Why 10: per image, the
  /// filter's estimate jitters by more than a drift moves it, and the LSTM then learns the jitter's mean reversion,
  /// not the trend, and drives t_d against the drift while the noise adapter makes up for it (docs/ton.md, "TPN's
  /// labels").
  int tpn_label_images = 10;
};

struct UpdateOptions {
  /// Measurement Jacobians at each clone's first estimate (OpenVINS' FEJ). Measured both ways (docs/results.md):
  /// with it orientation stays consistent, without it APE was lower on two of three simulations but yaw
  /// over-confident.
  bool measurement_fej = true;
  int max_clones = 20; ///< 1 s at 20 Hz: MSCKF-only accuracy and consistency improve markedly over 11
  /// The MSCKF updater's own options (update/update_options.h); its td_velocity_debias is YAML
  /// time_offset.velocity_debias (image-plane modes; 1 for independent pixel errors of the declared σ, as the
  /// feature-level simulations have; KLT's correlated errors make the bias ~0.03 of that, so 0, off, for images;
  /// docs/ton.md "Errors in variables"), its readout_state_velocity calibration.readout_state_velocity.
  UpdaterMSCKFOptions msckf;
};

/// SLAM features (update/updater_slam.h): features tracked through the whole window become landmarks in the state.
struct SlamOptions {
  int max_features = 0;        ///< landmarks in the state at most (0: MSCKF only; OpenVINS' default is 50)
  int max_init_per_frame = 10; ///< delayed initialisations per image at most
  UpdaterSlamOptions updater;  ///< update/update_options.h
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

/// Stop the run (ovton::core::EstimatorFailure) when the estimate has evidently diverged (core/filter_health.h). Off
/// only to watch a divergence to its end; a non-finite state stops the run either way.
struct HealthOptions {
  bool enabled = true;
};

/// Which of a recording's cameras a run uses.
struct RigOptions {
  /// At most this many (cam0, cam1, ... in order); 0: every camera the recording has, 1: monocular.
  int max_cameras = 0;
};

struct VioOptions {
  RigOptions rig;
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
