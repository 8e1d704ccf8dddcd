#pragma once
// Calibration of a recording that comes without one (`ovton calibrate`): the camera-IMU rotation R_IC, the focal
// length, the time offset t_d and the rolling shutter's readout time, from a natural scene, by comparing the images'
// rotation with the gyro's. Rotation needs no depth: a distant point seen in two images satisfies
//     b_0 ∝ R_{C0 C1} b_1,   R_{C0 C1} = R_ICᵀ · R_{I(τ0) I(τ1)} · R_IC,
// with b = ((u − c_u)/f, (v − c_v)/f, 1) and τ the IMU-clock instant the feature's row was exposed:
//     τ = t_cam + t_d + (v/H − ½)·t_r        (the filter's readout convention: t_d belongs to the middle row).
// A walking user also translates; the parallax that adds is handled two ways (CalibOptions::model): a robust loss on
// the pure-rotation reprojection (Huber, the translation's parallax down-weighted as outliers), or per image pair an
// epipolar residual whose translation direction is solved linearly given the rotation.
//
// The fit: a coarse grid over t_d (the images' rotation rates against the gyro's mean rates, R_IC in closed form per
// candidate), then Levenberg-Marquardt over (R_IC, f, t_d, t_r, gyro bias) on every feature with numeric derivatives.
// The σ are a sandwich (cluster-robust by image pair, Bartlett-weighted over neighbouring pairs): the features of one
// pair share its translation, and consecutive pairs share the motion, so a curvature-only σ would be several times too
// small.
#include "ov_core/io/dataset.h"
#include "ov_core/types/sensor_data.h"

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace ovton::msckf {

/// Two images and the pixels (as recorded, no distortion model) of the features tracked between them.
struct CalibPair {
  int64_t t0_cam_ns = 0, t1_cam_ns = 0;
  std::vector<Eigen::Vector2d> uv0, uv1;
};

enum class CalibModel { Rotation, Epipolar };
/// "rotation" | "epipolar"; throws UsageError otherwise.
CalibModel parse_calib_model(const std::string &s);
std::string to_string(CalibModel m);

struct CalibOptions {
  /// The unknown camera's prior: this horizontal field of view gives the starting focal length (phones: 60-75°).
  double hfov_prior_deg = 67.5;
  double td_range_s = 0.2; ///< coarse grid: prior ± range
  double td_step_s = 0.002;
  double td_prior_s = 0.0;
  bool estimate_readout = true;
  CalibModel model = CalibModel::Epipolar;
  double huber_px = 1.5;          ///< Huber threshold of the per-feature residual [px]
  int max_features_per_pair = 60; ///< evenly thinned: a pair's features share its motion, more add little
  int min_features_per_pair = 15; ///< fewer: the pair is left out
  int max_iterations = 50;        ///< Levenberg-Marquardt
  int sigma_lag_pairs = 15;       ///< Bartlett window of the sandwich covariance over neighbouring pairs (~0.5 s)
  /// Pairs whose gyro rotation is below this [rad] are left out of the fine fit: they carry no rotation and only
  /// parallax (they still count for nothing in R_IC or f).
  double min_pair_rotation_rad = 0.005;
  /// Delete-one-block jackknife over this many stretches of the recording (0: off); each σ is the larger of it and
  /// the sandwich.
  int jackknife_blocks = 8;
  /// Refine a calibration already known instead of searching (has_start): the fit starts here, the grid is skipped.
  bool has_start = false;
  Eigen::Matrix3d start_R_IC = Eigen::Matrix3d::Identity();
  double start_focal_px = 0, start_td_s = 0, start_readout_s = 0;
};

struct CalibResult {
  int width = 0, height = 0;
  Eigen::Matrix3d R_IC = Eigen::Matrix3d::Identity();      ///< camera -> IMU
  Eigen::Vector3d sigma_rot_rad = Eigen::Vector3d::Zero(); ///< of the rotation error Exp(δ)·R_IC, IMU frame
  double focal_px = 0, sigma_focal_px = 0;
  double cu = 0, cv = 0;           ///< principal point: the image centre (not estimated)
  double td_s = 0, sigma_td_s = 0; ///< t_imu = t_cam + t_d, middle row
  double readout_s = 0, sigma_readout_s = 0;
  bool readout_estimated = false;
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero(), sigma_gyro_bias = Eigen::Vector3d::Zero(); ///< [rad/s]
  double coarse_td_s = 0;                                    ///< the grid's best candidate
  Eigen::Matrix3d coarse_R_IC = Eigen::Matrix3d::Identity(); ///< R_IC fitted to the rates there (prior focal)
  double robust_cost = 0;
  /// The two σ behind each reported one (rotation as the norm of its three): sandwich and jackknife, each
  /// (rotation [rad], focal [px], t_d [s], readout [s]); the jackknife's refits' t_d.
  Eigen::Vector4d sigma_sandwich = Eigen::Vector4d::Zero(), sigma_jackknife = Eigen::Vector4d::Zero();
  std::vector<double> jackknife_td_s;
  double robust_cost_unused_ = 0;     ///< Huber cost at the solution (sum over residuals, px^2)
  std::vector<double> coarse_profile; ///< trimmed cost per grid candidate (prior − range ... + range)
  double focal_prior_px = 0;
  int pairs_total = 0, pairs_used = 0;
  long features_used = 0;
  double rms_px = 0;       ///< RMS of the residuals within 3 Huber thresholds
  double inlier_share = 0; ///< share of residuals within the Huber threshold
  int iterations = 0;
  double seconds = 0;
  /// Correlation of t_d with the other parameters (R_IC x y z, f, t_r) from the covariance.
  Eigen::Matrix<double, 6, 6> correlation = Eigen::Matrix<double, 6, 6>::Identity();
  std::string summary() const; ///< the multi-line report `ovton calibrate` prints
};

/// The fit over pairs already tracked. `imu` time-ordered (IMU clock); `width`, `height` of the images. Throws
/// DataError (naming `source`) when too few pairs carry rotation or the IMU does not cover the images.
CalibResult calibrate_camera_imu(const std::vector<CalibPair> &pairs, const std::vector<ovton::core::ImuData> &imu,
                                 int width, int height, const CalibOptions &opt, const std::string &source);

/// Decodes an image (8-bit gray).
using CalibImageLoader = std::function<cv::Mat(const ovton::core::ImageEntry &)>;

/// KLT tracks between consecutive images (images [first, last) of `images`), with a pinhole guess of focal `f_px`
/// for the tracker's RANSAC. Features are pixels as recorded.
std::vector<CalibPair> track_calib_pairs(const std::vector<ovton::core::ImageEntry> &images, size_t first, size_t last,
                                         int width, int height, double f_px, const CalibImageLoader &load);

/// The whole calibration of a recording loaded without calibration (load_euroc_streams): its images taken from
/// `from_s` to `to_s` seconds after the first one (to_s <= 0: to the end) are decoded (any format the codecs read,
/// colour converted to gray), tracked and fitted against its IMU. The images' size is the first image's. Throws
/// DataError naming an unreadable image, or the folder when the data cannot calibrate.
CalibResult calibrate_recording(const ovton::core::Dataset &d, double from_s, double to_s, const CalibOptions &opt);

/// The IMU noise the log shows, where no sensor.yaml says it.
struct ImuNoiseEstimate {
  bool still_found = false; ///< a still stretch of `window_s` was found, from which the white noise is measured
  double still_begin_s = 0; ///< seconds after the first reading
  double window_s = 1.0;
  double gyro_std = 0, accel_std = 0; ///< per axis, over the still stretch [rad/s, m/s^2]
  double rate_hz = 0;                 ///< the readings' median rate
  ovton::core::ImuCalib calib;        ///< what is written (measured where measured, conservative defaults otherwise)
  std::string summary() const;
};
/// Looks for the stillest window of the log; its per-axis standard deviations give the white-noise densities
/// (σ/√rate), inflated to at least the phone defaults. The random walks are never observable from one stretch: the
/// conservative defaults are written and said so.
ImuNoiseEstimate estimate_imu_noise(const std::vector<ovton::core::ImuData> &imu);

} // namespace ovton::msckf
