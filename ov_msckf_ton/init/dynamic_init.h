#pragma once
// Dynamic initialisation: the IMU state of a platform that is already moving, from a short window of tracked features
// and IMU readings, without ground truth. Same maths as OpenVINS' dynamic initialiser (Geneva et al.), reimplemented:
//
// Over a window of ~1 s the IMU alone gives each frame's orientation and position relative to the first IMU frame I0
// up to the unknowns x = (v0, g0, b_g, b_a): R_k = ΔR_k(b_g), p_k = v0 t_k + ½ g0 t_k² + Δp_k(b_g, b_a), with v0 the
// velocity and g0 gravity in I0, ΔR, Δp the pre-integrated gyro and accelerometer readings. Every tracked feature p_f
// (in I0) must project onto its observations. With the biases held, the projections are linear in (p_f, v0, g0)
// (bearing × point = 0), which gives a closed-form start with |g0| = g imposed by a Lagrange multiplier; a
// Gauss-Newton / Levenberg-Marquardt refinement of the reprojection errors then estimates everything, biases
// included. Scale is not a separate unknown: Δp is metric. The refinement's information matrix gives the covariance.
#include "ov_core/types/sensor_data.h"
#include "ov_msckf_ton/init/init_options.h"

#include <Eigen/Core>
#include <deque>
#include <string>
#include <utility>
#include <vector>

namespace ovton::msckf {

/// Features seen in one image: (feature id, undistorted normalised coordinates), and the image's IMU-clock time.
struct InitFrame {
  int64_t t_cam_ns = 0;
  int64_t t_imu_ns = 0;
  std::vector<std::pair<size_t, Eigen::Vector2d>> obs;
};

struct DynamicInitResult {
  bool ok = false;
  std::string why; ///< reason when !ok; a summary when ok
  /// State at the newest frame's IMU time, in a gravity-aligned world (z up) whose yaw follows I0's x axis.
  Eigen::Matrix3d R_WB = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero(), v_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero(), ba = Eigen::Vector3d::Zero();
  /// Covariance of [δθ δp δv δb_g δb_a] in the filter's error convention (state.h).
  Eigen::Matrix<double, 15, 15> P = Eigen::Matrix<double, 15, 15>::Zero();
  int features = 0, frames = 0, iterations = 0;
  double rms_px = 0.0, disparity_px = 0.0;
  double sigma_rollpitch_deg = 0.0, sigma_vel = 0.0;                   ///< marginal, from P before the inflation
  double sigma_rollpitch_given_ba_deg = 0.0, sigma_vel_given_ba = 0.0; ///< with b_a held: what the gate checks
};

/// `frames` oldest first (the newest is the state's time); `imu` must cover them. T_BC camera -> body; focal_px
/// converts normalised residuals to pixels. sigma_yaw and sigma_pos are added to the unobservable directions.
DynamicInitResult dynamic_initialize(const std::vector<InitFrame> &frames, const std::deque<ovton::core::ImuData> &imu,
                                     const Eigen::Matrix4d &T_BC, double focal_px, double gravity_mag, double sigma_yaw,
                                     double sigma_pos, double sigma_px, const DynamicInitOptions &opt);

/// Pre-integrated IMU from t0 to each time in `t_ns` (sorted, all ≥ t0) with biases removed: orientation of the body
/// at t relative to t0, and velocity / position change in the t0 body frame without gravity. Readings are
/// interpolated at the ends; midpoint rule as in the propagator. Returns false when the readings do not cover them.
struct Preintegrated {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d v = Eigen::Vector3d::Zero(), p = Eigen::Vector3d::Zero();
};
bool preintegrate(const std::deque<ovton::core::ImuData> &imu, int64_t t0_ns, const std::vector<int64_t> &t_ns,
                  const Eigen::Vector3d &bg, const Eigen::Vector3d &ba, std::vector<Preintegrated> &out);

} // namespace ovton::msckf
