#pragma once
// IMU propagation of the mean and the error-state covariance between IMU-clock times.
#include "ov_core/types/imu_buffer.h"
#include "ov_core/types/sensor_data.h"
#include "ov_msckf_ton/state/state.h"

namespace ovton::msckf {

/// Continuous-time IMU noise (EuRoC imu0/sensor.yaml units). The time offset's process noise belongs to its model
/// (td/td_model.h).
struct ImuNoise {
  double sigma_w = 1.6968e-04;  ///< gyro white noise, rad/s/sqrt(Hz)
  double sigma_a = 2.0e-3;      ///< accel white noise, m/s^2/sqrt(Hz)
  double sigma_wb = 1.9393e-05; ///< gyro bias random walk, rad/s^2/sqrt(Hz)
  double sigma_ab = 3.0e-3;     ///< accel bias random walk, m/s^3/sqrt(Hz)
};

using Mat15 = Eigen::Matrix<double, 15, 15>;

/// One propagation step over dt with gyro/accel readings held constant (the caller passes the mean of the two
/// readings that bound the interval). Mean, with ω = ω_m − b_g, a = a_m − b_a, R_mid = R·Exp(ω dt/2):
///   R' = R·Exp(ω dt),  v' = v + (R_mid a + g) dt,  p' = p + v dt + ½ (R_mid a + g) dt²
/// Phi is the exact first-order Jacobian of this discrete map in the error-state convention of state.h
/// (use_fej = false), or its FEJ form with x's first estimates of v and p (use_fej = true); Q the discrete noise
/// (white noise as variance density/dt per sample, bias random walks as density²·dt).
void imu_step(const ImuState &x, const Eigen::Vector3d &wm, const Eigen::Vector3d &am, double dt,
              const Eigen::Vector3d &gravity, const ImuNoise &noise, ImuState &out, Mat15 *Phi, Mat15 *Q,
              bool use_fej = false);

/// IMU scale and misalignment (online calibration): ω = D_w (ω_m − b_g), a = D_a (a_m − b_a), D lower-triangular.
struct ImuIntrinsics {
  Eigen::Matrix3d D_w = Eigen::Matrix3d::Identity(), D_a = Eigen::Matrix3d::Identity();
};
using Mat15x12 = Eigen::Matrix<double, 15, 12>;

/// imu_step with the readings corrected by `D` before use. Phi_cal, when given, is the Jacobian of the step w.r.t.
/// the 12 lower-triangle entries of [D_w D_a] (state.h order): δω = D_w δ(−b_g) + δD_w (ω_m − b_g), likewise a.
void imu_step_calibrated(const ImuState &x, const ImuIntrinsics &D, const Eigen::Vector3d &wm,
                         const Eigen::Vector3d &am, double dt, const Eigen::Vector3d &gravity, const ImuNoise &noise,
                         ImuState &out, Mat15 *Phi, Mat15 *Q, Mat15x12 *Phi_cal, bool use_fej = false);

class Propagator {
public:
  Propagator(const ImuNoise &noise, double gravity_mag = 9.81);
  /// First-estimate Jacobians in propagation (on by default; off only to measure what they change).
  void set_use_fej(bool on) { use_fej_ = on; }

  void feed_imu(const ovton::core::ImuData &m);

  /// Propagates the IMU state (mean and covariance, with its cross terms) from s.t_imu_ns to t_to_ns (IMU clock).
  /// Readings are interpolated at both ends. t_d is left to its model (td/td_model.h).
  /// Returns false (state untouched) when the IMU buffer does not reach t_to_ns.
  bool propagate(State &s, int64_t t_to_ns);

  /// Mean-only propagation of a copy (no covariance), e.g. to predict a pose.
  bool predict_mean(const State &s, int64_t t_to_ns, ImuState &out) const;

  /// Bias-corrected body angular velocity and raw accel at the end of the last propagation.
  const Eigen::Vector3d &last_w_B() const { return last_w_B_; }
  const Eigen::Vector3d &gravity() const { return gravity_; }
  const ImuNoise &noise() const { return noise_; }
  /// The readings fed so far (the last 5 s of them).
  const ovton::core::ImuBuffer &imu() const { return imu_; }

private:
  ImuNoise noise_;
  Eigen::Vector3d gravity_;
  ovton::core::ImuBuffer imu_;
  Eigen::Vector3d last_w_B_ = Eigen::Vector3d::Zero();
  bool use_fej_ = true;
};

} // namespace ovton::msckf
