#pragma once
// Measures a real IMU log against its ground truth, so that the synthetic IMU can be made as unkind as the real one
// (`ovton simulate --match-imu`, docs/simulate.md "IMU error model").
//
// What the ground truth gets wrong is kept apart from what the IMU gets wrong:
//  - ground truth: its time alignment to the IMU clock (a shift), the rotation between its body frame and the IMU's
//    axes (the common rotation of the gyro and accelerometer fits), and the tilt of its world frame against gravity;
//  - IMU: per-axis scale and non-orthogonality (the symmetric part of each fit), turn-on biases, slow bias changes,
//    and the noise at frequencies the ground truth cannot carry (> ~10 Hz), on the ground and in flight, where the
//    rotors shake the airframe.
// The ideal IMU comes from the same smoothing spline the simulator renders along, so its smoothing is what a
// synthetic run would see too.
#include "ov_core/types/sensor_data.h"
#include <Eigen/Core>
#include <string>
#include <vector>

namespace ovton::sim {

struct ImuMatchOptions {
  double knot_dt_s = 0.1;        ///< spline knots of the ground-truth fit (as the simulator's default)
  double max_shift_s = 0.05;     ///< search the ground truth's time shift in [-max, +max]
  double flight_speed_mps = 0.1; ///< "in flight" above this ground-truth speed (idle rotors below)
  double still_speed_mps = 0.02; ///< "still" below this speed (and below still_rate_rps)
  double still_rate_rps = 0.05;
  double high_band_hz = 20.0; ///< noise density measured from this frequency to 0.45 x the rate
};

/// Noise of one sensor in one regime: white-equivalent density in a band [unit/sqrt(Hz)].
struct BandDensity {
  double low_hz = 0.0, high_hz = 0.0;
  Eigen::Vector3d density = Eigen::Vector3d::Zero();
  size_t samples = 0;
};

struct ImuMatchReport {
  size_t samples = 0; ///< IMU readings used (inside the ground truth's span)
  double duration_s = 0.0;
  // Ground truth (not the IMU's doing).
  double gt_shift_s = 0.0;    ///< the IMU reading at t matches the ground truth at t + shift (gyro)
  double accel_delay_s = 0.0; ///< the accelerometer's extra shift against the gyro (an IMU property)
  Eigen::Vector3d gt_rotation = Eigen::Vector3d::Zero(); ///< rotation vector, ground-truth body -> IMU axes [rad]
  Eigen::Vector2d gt_tilt = Eigen::Vector2d::Zero();     ///< world-frame tilt about x, y against gravity [rad]
  // The IMU.
  Eigen::Matrix3d gyro_S = Eigen::Matrix3d::Identity();    ///< symmetric scale/non-orthogonality: w_m = R S w + b
  Eigen::Vector3d gyro_rotation = Eigen::Vector3d::Zero(); ///< the gyro fit's rotation (= gt_rotation)
  /// Std of the ground truth's specific force per IMU axis: where it is small against the accelerometer's noise,
  /// the accelerometer's scale on that axis cannot be measured (it is not fitted; unit scale is assumed).
  Eigen::Vector3d accel_signal_std = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero(), accel_bias = Eigen::Vector3d::Zero(); ///< constant part
  Eigen::Vector3d gyro_bias_drift = Eigen::Vector3d::Zero(), accel_bias_drift = Eigen::Vector3d::Zero(); ///< std of
  ///< 10-s means of the residual about the constant bias (slow bias change plus the ground truth's slow errors)
  double bias_correlation_s = 0.0; ///< time for the 1-s residual means' autocorrelation to fall to 1/e (gyro)
  BandDensity gyro_still, accel_still, gyro_flight, accel_flight; ///< high-band noise, still and flying
  /// The in-flight residual's spectrum in octave-ish bands from 0.5 Hz: below ~5 Hz it mixes the IMU's errors with
  /// the ground truth's (and the spline's smoothing); above, it is the IMU's alone (noise and airframe vibration).
  std::vector<BandDensity> gyro_flight_spectrum, accel_flight_spectrum;
  Eigen::Vector3d gyro_fit_rms = Eigen::Vector3d::Zero(), accel_fit_rms = Eigen::Vector3d::Zero(); ///< all bands
  double imu_dt_jitter_s = 0.0; ///< std of the IMU's sample interval
};

/// imu: a real log (IMU clock), gt: its ground truth. Throws UsageError when they overlap by less than 20 s.
ImuMatchReport match_imu(const std::vector<ovton::core::ImuData> &imu, const std::vector<ovton::core::StateSample> &gt,
                         const ImuMatchOptions &opt = {});

/// The report as YAML (units in the keys), with a comment line per group saying whose error it is.
std::string imu_match_yaml(const ImuMatchReport &r);

} // namespace ovton::sim
