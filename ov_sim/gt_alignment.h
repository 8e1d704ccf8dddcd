#pragma once
// A fine ground truth expressed in a real IMU's frame and clock, so that semi-real folders are consistent.
//
// A semi-real folder (`ovton simulate --imu-from`) renders its images along a spline of a ground truth while its
// IMU log is the real one. EuRoC's state_groundtruth_estimate0 is a 20 Hz estimate: a spline through it (knots
// 0.1 s) misses the 1.5-20 Hz motion the real IMU recorded, so the images and the IMU disagree by exactly that
// motion (docs/simulate.md, "Semi-real folders"). A 200 Hz pose file (euroc_groundtruth/V1_01_easy.txt) carries it, but
// in its own body frame and clock: this module measures those against the real log (time shift, axes rotation
// and world tilt by match_imu's fits; the IMU's origin in the reference's body by a least-squares fit against an
// IMU-frame ground truth) and applies them, so that a spline with fine knots through the result follows the motion
// the IMU saw.
#include "ov_core/types/sensor_data.h"
#include <Eigen/Core>
#include <string>
#include <vector>

namespace ovton::sim {

struct GtAlignment {
  double shift_s = 0.0;                               ///< the IMU reading at t matches the reference at t + shift
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero(); ///< reference body -> IMU axes, rotation vector [rad]
  Eigen::Vector2d tilt = Eigen::Vector2d::Zero();     ///< the reference world's tilt about x, y against gravity [rad]
  Eigen::Vector3d lever_I = Eigen::Vector3d::Zero();  ///< IMU origin minus the reference's, in the IMU axes [m]
  bool lever_fitted = false;                          ///< false: no IMU-frame ground truth overlapped (lever 0)
  double lever_fit_rms_m = 0.0;                       ///< position residual of the lever-arm fit
  size_t lever_samples = 0;
};

/// Measures `ref` (poses, any rate; 200 Hz for the purpose above) against the real IMU log `imu` (fits on a spline
/// with knots knot_dt_s) and, where `imu_frame_gt` (a ground truth in the IMU's frame, e.g. EuRoC's
/// state_groundtruth_estimate0; may be empty) overlaps it, the IMU's origin in the reference body. Throws
/// UsageError when the log and the reference overlap by less than 20 s.
GtAlignment align_gt_to_imu(const std::vector<ovton::core::ImuData> &imu,
                            const std::vector<ovton::core::StateSample> &ref,
                            const std::vector<ovton::core::StateSample> &imu_frame_gt, double knot_dt_s);

/// `ref` moved into the IMU's clock (t - shift), world (tilt removed) and body (axes rotated, origin at the IMU).
/// Velocities and biases are dropped (the spline derives the motion; a pose file carries no biases).
std::vector<ovton::core::StateSample> apply_gt_alignment(const std::vector<ovton::core::StateSample> &ref,
                                                         const GtAlignment &a);

/// `fine` (already aligned) on top of `base`, an IMU-frame ground truth of the same flight (EuRoC's estimate, any
/// rate): below blend_hz the motion is base's (through a spline with knots base_knot_dt_s), above it fine's. At
/// fine's stamps inside base's span. Why: the estimate was made with the IMU, so its slow motion and its bias
/// columns agree with the real log, while a motion-capture pose file wanders against the log by ~0.005 rad/s over
/// seconds (V1_01: 0.4 deg median, 1.2 deg at most against the estimate); the fast motion only the pose file has.
std::vector<ovton::core::StateSample> blend_gt(const std::vector<ovton::core::StateSample> &base,
                                               const std::vector<ovton::core::StateSample> &fine, double blend_hz,
                                               double base_knot_dt_s);

/// One line for sim.yaml and the progress output: shift [ms], rotation [deg], tilt [deg], lever arm [mm].
std::string describe_gt_alignment(const GtAlignment &a);

} // namespace ovton::sim
