#pragma once
// The filter's own calibration at each image, from the calibration log `ovton run --residual-log` writes beside the
// residual log (ov_core/io/residual_log_schema.h): the rate design compares the images with the raw IMU through it,
// so that an effect the filter has estimated (camera-IMU rotation, IMU scale, readout, focal) is not named again
// (docs/diagnose.md, "The filter's calibration").
#include "ov_core/io/residual_log_schema.h"
#include "ov_core/types/sensor_data.h"

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace ovton::eval::diag {

using ovton::core::CalibrationLogRow;

/// The calibration the filter held for the image at t_cam_ns: the row of the first update at or after it (the first
/// that can have used the image), the last row after the log's end; nullptr when there are no rows.
const CalibrationLogRow *calibration_at(const std::vector<CalibrationLogRow> &rows, int64_t t_cam_ns);

/// A row-major 3 × 3 array as a matrix.
Eigen::Matrix3d mat3(const double *a);

/// The raw IMU through the filter's IMU intrinsics at each reading: ω_m -> D_w·ω_m, a_m -> D_a·a_m (the biases are left
/// in: the rate rows remove them per bin). The reading at IMU time t takes the calibration of camera time t − t̂_d.
std::vector<ovton::core::ImuData> imu_through_calibration(const std::vector<ovton::core::ImuData> &imu,
                                                          const std::vector<CalibrationLogRow> &rows);

/// Gyro reading at IMU time t_ns (linear interpolation; clamped at the ends).
Eigen::Vector3d gyro_at(const std::vector<ovton::core::ImuData> &imu, double t_ns);

/// The body's rotation R_{B0 B1} from IMU time t0_ns to t1_ns: the gyro less `bias` (ovton::core::imu_rotation), the
/// rate held at the end readings beyond them.
Eigen::Matrix3d body_rotation(const std::vector<ovton::core::ImuData> &imu, double t0_ns, double t1_ns,
                              const Eigen::Vector3d &bias = Eigen::Vector3d::Zero());

/// The filter's relative focal error ε̂ = ½·(f̂u/fu + f̂v/fv) − 1 against the nominal fu, fv, when it estimated the
/// intrinsics (0 otherwise).
double focal_estimate(const CalibrationLogRow &row, double fu, double fv);

} // namespace ovton::eval::diag
