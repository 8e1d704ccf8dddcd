#pragma once
// Trajectory evaluation (paper §V-A): alignment, APE/ARE, RPE, TPE (eq. 16), CIT (eq. 15).
#include "ov_core/types/sensor_data.h"
#include <string>
#include <vector>

namespace ovton::eval {

enum class AlignMode { None, PosYaw, SE3, Sim3 };
AlignMode
parse_align_mode(const std::string &s); ///< "none" | "posyaw" | "se3" | "sim3"; throws ovton::core::UsageError
const char *to_string(AlignMode m);     ///< the same strings parse_align_mode accepts

/// Transform (rigid, yaw-only, or with scale for sim3) mapping the estimate frame into the ground-truth frame.
struct Alignment {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  double s = 1.0; ///< scale; differs from 1 only for sim3, where it measures the estimate's scale error
  Eigen::Vector3d apply(const Eigen::Vector3d &p) const { return s * (R * p) + t; }
};

/// Pairs of estimate and ground truth at the estimate's stamps (ground truth interpolated:
/// linear in position and velocity, slerp in orientation). Estimates outside the truth's span, or in a gap of the
/// truth longer than max_gap_s, are dropped. An interpolated truth sample has orientation only when both of its
/// neighbours do. Throws UsageError when either input is empty, the truth is not strictly increasing in time,
/// or no estimate survives (which names both time spans, the usual cause being a clock or unit mismatch).
struct Association {
  std::vector<ovton::core::StateSample> est;
  std::vector<ovton::core::StateSample> gt;
};
Association associate(const std::vector<ovton::core::StateSample> &est, const std::vector<ovton::core::StateSample> &gt,
                      double max_gap_s = 0.1);

/// True offset at camera-clock time t_cam_ns: linear between truth samples, held constant beyond the ends.
/// `td` must not be empty.
double td_truth_at(const std::vector<ovton::core::TdSample> &td, int64_t t_cam_ns);

/// Transform with gt.p ~= s R est.p + t, fitted on positions only (so it works with position-only truth).
/// SE3: Umeyama without scale, reflection fixed. Sim3: Umeyama with scale (s < 1: the estimate is too large). PosYaw:
/// translation + rotation about world z only, closed form theta = atan2(sum(x_e*y_g - y_e*x_g), sum(x_e*x_g + y_e*y_g))
/// on centred points. None: identity. Throws UsageError on an empty association.
Alignment align(const Association &a, AlignMode mode);

struct RpeResult {
  double segment_m = 0.0; ///< segment length along the ground-truth path
  int count = 0;          ///< number of segments; the RMSEs are NaN when 0
  double trans_rmse_m = 0.0;
  double rot_rmse_deg = 0.0; ///< NaN when the truth is position-only
};

struct CitOptions {
  double eps1_s = 1e-3;          ///< |td - target| <= eps1
  double eps2_s = 1e-4;          ///< |td(k) - td(k-1)| <= eps2
  bool target_from_truth = true; ///< target = td truth at frame k when a truth file is given
  double target_s = 0.0;         ///< used when target_from_truth is false
};

struct EvalResult {
  int n_est = 0;
  int n_matched = 0;
  AlignMode align_mode = AlignMode::PosYaw;
  Alignment alignment;
  double ape_rmse_m = 0.0;
  double ape_mean_m = 0.0;
  double ape_max_m = 0.0;
  double are_rmse_deg = 0.0; ///< NaN when ground truth is position-only
  std::vector<RpeResult> rpe;
  bool has_tpe = false;
  int tpe_count = 0; ///< estimate frames that entered the TPE
  double tpe_rmse_mm = 0.0;
  /// With has_tpe: RMSE of t̂_d − t_d over all rows and over the second half of them (past convergence) [ms], and
  /// the mean of (t̂_d − t_d)² / σ² over rows with σ > 0 (t_d NEES, 1 is ideal; NaN when no row has a σ).
  double td_err_rmse_ms = 0.0, td_err_rmse_late_ms = 0.0, td_nees = 0.0;
  bool has_cit = false;
  int cit = -1;                       ///< frame index of convergence, -1 if never
  std::vector<double> ape_per_pose_m; ///< aligned position error at each matched estimate
};

struct EvalOptions {
  AlignMode align = AlignMode::PosYaw;
  double max_gap_s = 0.1; ///< see associate()
  std::vector<double> rpe_segments_m = {1, 2, 4, 8, 16};
  CitOptions cit;
};

/// td_truth may be empty: TPE and CIT (with truth target) are then skipped. TPE and CIT use the estimate rows
/// that carry a time offset (has_td), in their order; CIT is the index into that sequence. td_truth is keyed by
/// camera-clock stamp, estimates by the IMU clock, so the truth is looked up at t_cam = t_imu - td_hat (linear
/// interpolation, clamped at the ends). The estimate must be strictly increasing in time (UsageError otherwise).
EvalResult evaluate(const std::vector<ovton::core::StateSample> &est, const std::vector<ovton::core::StateSample> &gt,
                    const std::vector<ovton::core::TdSample> &td_truth, const EvalOptions &opt);

} // namespace ovton::eval
