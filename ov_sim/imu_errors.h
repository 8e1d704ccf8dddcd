#pragma once
// IMU errors beyond the datasheet's white noise and bias random walk (imu_synth.h), as a real multicopter IMU shows
// them against its ground truth (imu_match.h, docs/simulate.md "IMU error model"): gyro scale and axis
// misalignment, turn-on biases, and coloured noise whose spectrum follows the measured one - the airframe's
// vibration from the rotors in flight (weaker with idle rotors on the ground) and a low-frequency wander of the
// readings (bias instability) far above what the datasheet's white noise and bias random walk give.
#include "ov_core/cam/camera_calib.h"
#include "ov_core/types/sensor_data.h"
#include "ov_sim/trajectory.h"
#include <Eigen/Core>
#include <string>
#include <vector>

namespace ovton::sim {

/// One band of a one-sided noise spectrum: white-equivalent density per axis between low_hz and high_hz.
struct NoiseBand {
  double low_hz = 0.0, high_hz = 0.0;
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();  ///< [rad/s/sqrt(Hz)]
  Eigen::Vector3d accel = Eigen::Vector3d::Zero(); ///< [m/s^2/sqrt(Hz)]
};

struct ImuErrorModel {
  bool enabled = false;
  Eigen::Matrix3d gyro_scale_misalignment = Eigen::Matrix3d::Identity();                       ///< w_m = S w + ...
  Eigen::Vector3d gyro_bias0 = Eigen::Vector3d::Zero(), accel_bias0 = Eigen::Vector3d::Zero(); ///< turn-on biases
  /// In-flight spectrum of the noise (bands must not overlap; below the first band the first band's level is
  /// used down to 0 Hz, above the last nothing). The datasheet white noise already drawn is subtracted, so that
  /// the total follows the spectrum where it lies above the datasheet.
  std::vector<NoiseBand> flight_spectrum;
  double ground_gyro_ratio = 1.0, ground_accel_ratio = 1.0; ///< noise on the ground (idle rotors) / in flight
  double flight_speed_mps = 0.1;                            ///< in flight while the speed exceeds this within +-2 s
};

/// Throws UsageError naming what is out of range.
void check(const ImuErrorModel &m);

/// Removes parts of the model, for ablations (`ovton simulate --imu-errors-drop`): a comma-separated list of
/// scale (scale and misalignment -> identity), turn-on (the turn-on biases), slow (bands below 2 Hz: bias wander),
/// mid (2-10 Hz), vibration (bands from 10 Hz), vibration-gyro / vibration-accel (those bands of one sensor only).
/// Throws UsageError for an unknown part.
void drop_imu_error_parts(ImuErrorModel &m, const std::string &parts);

/// Adds the model's errors to a synthetic log (its stamps, in order) and the turn-on biases to the truth's biases.
/// `white_gyro`/`white_accel` are the densities of the white noise already in the log. Deterministic in `seed`.
void add_imu_errors(const Trajectory &traj, const ImuErrorModel &m, double white_gyro, double white_accel,
                    uint64_t seed, std::vector<ovton::core::ImuData> &imu,
                    std::vector<ovton::core::StateSample> &truth);

/// Allan variance [unit^2] at averaging time tau_s of one axis of the noise a synthetic log carries: the datasheet
/// white noise `white` and bias random walk `walk` (EuRoC sensor.yaml units) together with the model's coloured
/// noise (its flight spectrum; where that lies below `white`, the white noise), sampled at rate_hz (its Nyquist
/// frequency bounds the spectrum). `gyro` picks the sensor.
double allan_variance(const ImuErrorModel &m, bool gyro, int axis, double white, double walk, double tau_s,
                      double rate_hz = 200.0);

/// The white noise density and bias random walk a filter should be told for a synthetic IMU with the datasheet
/// noise `datasheet` plus the errors of `m`: fitted to the log's Allan variance (averaged over the axes: the filter's
/// noise is isotropic) over averaging times [tau_min_s, tau_max_s], by least squares on the log of the Allan variance
/// on a log grid — how a real IMU's noise parameters are obtained (Allan variance of a log). Without `m`'s coloured
/// noise the datasheet values come back (to the fit's accuracy). Only the four noise values of the result are set.
ovton::core::ImuCalib fitted_imu_noise(const ImuErrorModel &m, const ovton::core::ImuCalib &datasheet,
                                       double tau_min_s = 0.05, double tau_max_s = 20.0);

/// The model measured on the real V1_01_easy log against EuRoC's own ground truth (docs/simulate.md has the
/// command and the numbers): what `--realism euroc` uses.
ImuErrorModel euroc_v1_01_imu_errors();

} // namespace ovton::sim
