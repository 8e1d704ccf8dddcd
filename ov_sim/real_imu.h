#pragma once
// The real IMU of a semi-real folder (`ovton simulate --imu-from`, `--align-gt`): where it is read from, and which
// biases the folder's ground truth gives it.
//
// The source is an EuRoC folder (mav0/imu0/data.csv and, where present, its IMU-frame ground truth
// state_groundtruth_estimate0/data.csv; no images needed) or a flat imu0 log such as
// ../shared/data/euroc_imu0/MH03.csv. The ground truth's bias columns are what `--init groundtruth` starts the filter
// from, so a real log whose biases are unknown would start it ~0.08 rad/s off on the ADIS16448's z gyro: they come from
// the first source that has them.
#include "ov_core/types/sensor_data.h"
#include <Eigen/Core>
#include <string>
#include <vector>

namespace ovton::sim {

struct RealImu {
  std::vector<ovton::core::ImuData> imu;
  std::vector<ovton::core::StateSample> groundtruth; ///< IMU frame and clock; empty for a flat log
};

/// `path`: an EuRoC folder (the one holding mav0/, or mav0/ itself) or a flat log in EuRoC's imu0/data.csv format,
/// whose rate comes from a sensor.yaml beside it (else 200 Hz). Throws DataError for a missing or malformed log.
RealImu load_real_imu(const std::string &path);

/// Biases of the real IMU for the folder's ground truth.
struct RealImuBiases {
  std::vector<ovton::core::StateSample> samples; ///< per-instant biases (bias columns); empty: the constants below
  Eigen::Vector3d bg = Eigen::Vector3d::Zero(), ba = Eigen::Vector3d::Zero();
  std::string source; ///< for sim.yaml
  /// Biases at t: of the first sample at or after t (the last one past the end), or the constants.
  void at(int64_t t_ns, Eigen::Vector3d &bg_out, Eigen::Vector3d &ba_out) const;
};

/// From the first of: the real source's ground truth, `gt` (the --gt trajectory as read, e.g. a 17-column EuRoC
/// estimate) when they carry bias columns; else the log's constant biases measured against `gt` (match_imu, spline
/// knots knot_dt_s). `gt_name` names --gt in `source`.
RealImuBiases real_imu_biases(const RealImu &real, const std::vector<ovton::core::StateSample> &gt,
                              const std::string &gt_name, double knot_dt_s);

} // namespace ovton::sim
