#pragma once
// Writes a synthetic EuRoC-format folder: mav0/{cam0,imu0,state_groundtruth_estimate0,td_truth} + sim.yaml.
#include "ov_core/cam/camera_calib.h"
#include "ov_sim/camera_effects.h"
#include "ov_sim/feature_sim.h"
#include "ov_sim/imu_errors.h"
#include "ov_sim/imu_synth.h"
#include "ov_sim/renderer.h"
#include "ov_sim/scene.h"
#include "ov_sim/td_model.h"
#include "ov_sim/trajectory.h"
#include <functional>
#include <memory>
#include <string>

namespace ovton::sim {

struct SimOptions {
  std::string out_dir;
  std::string gt_file; ///< ground truth to follow; empty: the built-in Lissajous flight
  /// An EuRoC folder whose real IMU log (and IMU-frame ground truth, for the lever arm) gt_file is first moved onto:
  /// its clock, axes, gravity and origin (gt_alignment.h). For a fine reference that a semi-real folder's images
  /// follow as closely as the real IMU does. Empty: gt_file as it is.
  std::string align_gt_to;
  /// With align_gt_to's own ground truth: below this frequency the motion is that ground truth's, above it gt_file's
  /// (blend_gt). 0: gt_file's alone.
  double align_blend_hz = 1.5;
  double agility = 0.0; ///< built-in flight only: faster roll/pitch/yaw oscillations (LissajousTrajectory)
  double start_s = 0.0; ///< from the first ground-truth pose
  double duration_s = 20.0;
  double knot_dt_s = 0.1;     ///< B-spline knot spacing of the trajectory fit
  double first_image_s = 0.1; ///< first image this long after the first IMU sample (IMU clock)
  uint64_t seed = 1;
  ovton::core::CameraCalib cam; ///< defaults to euroc_cam0_calib()
  /// 2: render cam1 too (a stereo rig, triggered with cam0: the same stamps), with calibration `cam1`.
  int cameras = 1;
  ovton::core::CameraCalib cam1; ///< defaults to euroc_cam1_calib()
  /// cam1 on a clock of its own: its image stamped t_cam (cam0's stamp: the driver pairs them) shows the scene at
  /// t_imu = t_cam + td1, td1 = cam1_td0_s + cam1_td_bias_s_per_s·(t_cam − first stamp), whatever cam0's offset does;
  /// written to mav0/td_truth_cam1/data.csv. Off: cam1 is triggered with cam0 (td1 = cam0's t_d).
  bool cam1_own_clock = false;
  double cam1_td0_s = 0.010;
  double cam1_td_bias_s_per_s = 0.0;
  ovton::core::ImuCalib imu; ///< defaults to euroc_imu0_calib()
  std::string cam_source = "builtin EuRoC cam0", imu_source = "builtin EuRoC imu0 (ADIS16448)";
  bool imu_noise = true;
  bool imu_bias_walk = true;
  std::string imu_from;     ///< semi-real: copy this real log (EuRoC folder or imu0 CSV file, real_imu.h) instead
  ImuErrorModel imu_errors; ///< synthetic IMU: errors beyond the datasheet (imu_errors.h); off by default
  /// imu0/sensor.yaml declares the noise the IMU really has: with imu_errors on, the white noise and bias walk fitted
  /// to the synthetic log's Allan variance (fitted_imu_noise); with imu_from (a real EuRoC ADIS16448 log) the same
  /// fit of the model measured on that IMU (euroc_v1_01_imu_errors); false: `imu`'s (the datasheet's) in any case.
  bool declare_imu_errors = true;
  TdModelOptions td; ///< its seed is derived from `seed`
  /// Rolling shutter: image row v (distorted pixel row, continuous) is exposed at the frame's IMU-clock instant
  /// + v / height · readout_s; the stamp (and td_truth) belongs to row 0. 0: global shutter.
  double readout_s = 0.0;
  /// Focal-length error: the data are made with focal lengths (1 + focal_error)·(fu, fv) of `cam`, while
  /// cam0/sensor.yaml keeps `cam`'s. A filter reading the yaml then has f too small by this factor.
  double focal_error = 0.0;
  /// Gyro scale error: imu0/data.csv reads (1 + gyro_scale)·ω; imu0/sensor.yaml does not say so.
  double gyro_scale = 0.0;
  /// Per-axis scale (diagonal) and misalignment (off-diagonal) of the gyro and the accelerometer: they read
  /// (1 + gyro_scale)·(I + gyro_M)·ω and (I + accel_M)·f (ImuSynthOptions); imu0/sensor.yaml does not say so.
  Eigen::Matrix3d gyro_M = Eigen::Matrix3d::Zero(), accel_M = Eigen::Matrix3d::Zero();
  /// Camera-IMU extrinsic error: the data are made with R_BC_true = Exp(extrinsic_rot)·R_BC and p_BC_true = p_BC +
  /// extrinsic_trans (both in the body frame), while cam0/sensor.yaml keeps `cam`'s T_BC.
  Eigen::Vector3d extrinsic_rot = Eigen::Vector3d::Zero();   ///< rotation vector [rad]
  Eigen::Vector3d extrinsic_trans = Eigen::Vector3d::Zero(); ///< [m]
  /// Realism preset the options below came from (realism.h): "clean" (these defaults), "euroc", "harsh", or
  /// "custom" once an option was changed by hand. Recorded in sim.yaml.
  std::string realism = "clean";
  std::string texture_from; ///< Room texture: posters cut from this EuRoC folder's cam0 frames (empty: procedural)
  SceneOptions scene;       ///< its seed is derived from `seed`
  RenderOptions render;     ///< the clean renderer's options (used when camera_effects is off)
  CameraEffectsOptions camera_effects; ///< exposure, blur, noise, ... (camera_effects.h); off by default
  FeatureSimOptions features;          ///< its seed is derived from `seed`
  bool features_only = false;          ///< write cam0/features.csv instead of images
  bool no_images = false;              ///< write neither images nor features (IMU, ground truth, stamps only)
  bool overwrite = false;              ///< replace an existing OUT/mav0 (otherwise refuse: stale images would mix in)

  SimOptions();
};

struct SimReport {
  size_t n_imu = 0, n_images = 0, n_observations = 0;
  size_t n_renderings = 0;         ///< sub-frame renderings (more than n_images when motion blur needs them)
  double render_seconds = 0.0;     ///< wall time spent rendering (excluding PNG encoding and disk)
  double render_cpu_seconds = 0.0; ///< CPU time of the rendering thread: one core's cost, whatever the load
  double total_seconds = 0.0;
  std::string trajectory;
};

/// Progress: (stage, done, total). Called often; the caller decides how much to print.
using SimProgress = std::function<void(const std::string &stage, size_t done, size_t total)>;

/// Trajectory from the options (ground-truth fit or built-in); throws UsageError/DataError on bad input.
std::unique_ptr<Trajectory> make_trajectory(const SimOptions &opt);

/// Camera pose in the world at a body sample: R_WC = R_WB R_BC, p_WC = p_WB + R_WB p_BC.
void camera_pose(const TrajectorySample &s, const Eigen::Matrix4d &T_BC, Eigen::Matrix3d &R_WC, Eigen::Vector3d &p_WC);

/// The camera the data are made with: `cam` with its focal lengths scaled by 1 + focal_error and its T_BC moved by
/// the extrinsic error.
ovton::core::CameraCalib true_camera(const SimOptions &opt);

/// IMU-clock instant at which image row `row` of a frame whose row 0 is exposed at t_imu_ns is exposed.
int64_t row_time_ns(int64_t t_imu_ns, double row, int height, double readout_s);

/// The camera's pose over the exposure of a frame whose row 0 is exposed at t_imu_ns (rolling when readout_s > 0).
FramePose frame_pose(const Trajectory &traj, const SimOptions &opt, int64_t t_imu_ns);

/// Scene around the trajectory (uses the options' scene seed).
Scene make_scene(const Trajectory &traj, const SimOptions &opt);

/// Writes the whole folder. Files are written stream-wise (rows flushed), so an interrupted run keeps every
/// image already listed in cam0/data.csv.
SimReport write_simulation(const SimOptions &opt, const SimProgress &progress = nullptr);

/// Whether imu0/sensor.yaml declares the realistic IMU model's fitted noise: declare_imu_errors is on and the log
/// carries imu_errors or is a real one (imu_from).
bool declares_fitted_imu_noise(const SimOptions &opt);

/// What imu0/sensor.yaml says of the IMU: `imu`, with the noise of the realistic IMU's model fitted
/// (fitted_imu_noise) when declares_fitted_imu_noise.
ovton::core::ImuCalib declared_imu(const SimOptions &opt);

/// Text of sim.yaml for these options (every parameter and the seed).
std::string sim_yaml(const SimOptions &opt, const Trajectory &traj, const std::string &imu_bias_source = "");

} // namespace ovton::sim
