#pragma once
// Every option of the estimator, with defaults; one YAML loader that prints what it loaded.
#include "ov_core/track/track_klt.h"
#include "ov_msckf_ton/core/td_mode.h"
#include "ov_msckf_ton/state/propagator.h"

#include <iosfwd>
#include <string>

namespace ov_msckf_ton {

enum class InitMode { Static, GroundTruth };

struct VioOptions {
  // Time offset (t_imu = t_cam + t_d).
  TdMode td_mode = TdMode::Sr;
  double td_init_s = 0.0;           ///< initial / fixed (off) value
  double td_sigma_init_s = 0.01;    ///< prior sigma when t_d is estimated
  double td_random_walk = 0.0;      ///< s/sqrt(s); 0 treats t_d as a constant (sr, sir, fvon)
  double td_random_walk_tpn = 2e-4; ///< s/sqrt(s) for tpn/ton: the offset is allowed to move (paper §IV-C)

  // Networks (paper Table I), trained online. Epochs are per training call, i.e. per frame; lower them to trade
  // accuracy for per-frame cost.
  int fvon_max_labels = 40;    ///< labels per FVON training call (ITS pairs / F2F points)
  int fvon_min_f2f_labels = 5; ///< F2F predicts for a frame only with this many labelled features in it
  /// A prediction for a first observation enters the update only if it agrees with the track's next measured
  /// velocity within this (px/s; 0 = no check). 80 px/s is ~3σ of a 1 px backward difference at 20 Hz.
  double fvon_gate_px_s = 80.0;
  int its_epochs = 1000;            ///< ITS-FVON epochs per call (Table I)
  int f2f_epochs = 1500;            ///< F2F-FVON epochs per call (Table I)
  int tpn_epochs = 1000;            ///< TPN epochs per frame (Table I)
  int tpn_min_labels = 5;           ///< TPN drives t_d only once its buffer holds this many estimates
  double td_rate_max = 0.001;       ///< s/s bound on TPN's J_td: 10x the paper's drift (0.1 ms/s), 1000 ppm
  double tpn_start_sigma_s = 0.001; ///< TPN learns from t̂_d only once its σ is below this (past convergence)

  /// Image-plane velocity of the tracked observations: "backward" is the paper's eq. 2 (previous observation);
  /// "central" leaves the observation's own noise out (see CentralVelocityProvider; not the paper's SIR).
  std::string sir_velocity = "backward";
  /// "none" (paper eq. 2): a track's first observation has no velocity, so a new feature constrains t_d only once
  /// that observation has left the window; "next": it takes the next observation's (NextForFirstVelocityProvider), so
  /// new features constrain t_d at once. In fvon/ton it covers the first observations FVON did not predict. Not the
  /// paper's SIR, hence off by default; measured in the README (it keeps the image-plane modes from diverging on a
  /// fast start).
  std::string sir_first_velocity = "none";

  // Window and update.
  /// Measurement Jacobians at each clone's first estimate (OpenVINS' FEJ). Measured both ways in the README: with it
  /// orientation stays consistent, without it APE was lower on two of three simulations but yaw over-confident.
  bool measurement_fej = true;
  int max_clones = 20;      ///< 1 s at 20 Hz: MSCKF-only accuracy and consistency improve markedly over 11 (README)
  int min_track_length = 3; ///< observations (at clones) a feature needs to enter an MSCKF update
  double min_parallax_deg = 0.2; ///< triangulation: features with less parallax over their track are not used
  double sigma_px = 1.0;         ///< pixel noise of a KLT observation
  double chi2_multiplier = 1.0;  ///< scales the 95% chi-square gate
  int max_features_per_update = 80;

  // Zero-velocity update: when the features do not move on the image the platform is taken as still, the state
  // gets a v = 0 measurement instead of a clone (no parallax would make every MSCKF feature untriangulable).
  bool zupt = true;
  double zupt_max_disparity_px = 0.5; ///< median feature motion since the previous frame below this = still
  double zupt_sigma_v = 0.02;         ///< m/s; covers the rotor vibration of a MAV standing on the ground

  // Front end.
  ov_core::TrackKLTOptions track;

  // IMU noise: from the dataset's sensor.yaml, multiplied by these (inflation is common practice for real IMUs).
  double imu_noise_multiplier = 1.0;
  double gravity_mag = 9.81;

  // Initialisation.
  InitMode init_mode = InitMode::Static;
  double init_window_s = 1.0;      ///< still IMU data averaged for gravity and gyro bias
  double init_max_accel_std = 1.0; ///< m/s^2: above this the platform is not still (EuRoC rotors idle: ~0.5)
  double init_max_gyro_std = 0.1;  ///< rad/s (EuRoC idle: ~0.04)
  double init_sigma_rollpitch = 0.01, init_sigma_yaw = 1e-4, init_sigma_pos = 1e-4, init_sigma_vel = 0.01;
  double init_sigma_bg = 0.005, init_sigma_ba = 0.05;

  std::string source; ///< file the options came from, "" for defaults
};

/// Loads a VioOptions YAML (keys as the struct members; unknown keys are an error naming the file).
/// When `print` is set, writes every loaded value there.
VioOptions load_vio_options(const std::string &file, std::ostream *print = nullptr);
void print_vio_options(const VioOptions &o, std::ostream &os);

} // namespace ov_msckf_ton
