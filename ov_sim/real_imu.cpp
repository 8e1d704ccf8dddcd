#include "ov_sim/real_imu.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/types/errors.h"
#include "ov_sim/imu_match.h"

#include <algorithm>
#include <filesystem>

namespace fs = std::filesystem;

namespace ovton::sim {

namespace {

bool carries_biases(const std::vector<ovton::core::StateSample> &g) {
  return !g.empty() && g.front().has_velocity;
}

} // namespace

RealImu load_real_imu(const std::string &path) {
  std::error_code ec;
  RealImu r;
  if (fs::is_regular_file(path, ec)) {
    const fs::path yaml = fs::path(path).parent_path() / "sensor.yaml";
    const double rate = fs::is_regular_file(yaml, ec) ? ovton::core::load_euroc_imu_yaml(yaml.string()).rate_hz : 200.0;
    r.imu = ovton::core::read_euroc_imu_csv(path, rate);
    return r;
  }
  if (!fs::is_directory(path, ec))
    throw ovton::core::DataError(path, "no IMU log here (an EuRoC folder or an imu0/data.csv file)");
  const fs::path mav0 = fs::is_directory(fs::path(path) / "mav0", ec) ? fs::path(path) / "mav0" : fs::path(path);
  const fs::path csv = mav0 / "imu0" / "data.csv", yaml = mav0 / "imu0" / "sensor.yaml";
  if (!fs::is_regular_file(csv, ec))
    throw ovton::core::DataError(csv.string(), "file not found (the real IMU log)");
  const double rate = fs::is_regular_file(yaml, ec) ? ovton::core::load_euroc_imu_yaml(yaml.string()).rate_hz : 200.0;
  r.imu = ovton::core::read_euroc_imu_csv(csv.string(), rate);
  const fs::path gt = mav0 / "state_groundtruth_estimate0" / "data.csv";
  if (fs::is_regular_file(gt, ec))
    r.groundtruth = ovton::core::read_trajectory(gt.string());
  return r;
}

void RealImuBiases::at(int64_t t_ns, Eigen::Vector3d &bg_out, Eigen::Vector3d &ba_out) const {
  if (samples.empty()) {
    bg_out = bg, ba_out = ba;
    return;
  }
  auto it = std::lower_bound(samples.begin(), samples.end(), t_ns,
                             [](const ovton::core::StateSample &a, int64_t t) { return a.t_ns < t; });
  if (it == samples.end())
    --it;
  bg_out = it->bg, ba_out = it->ba;
}

RealImuBiases real_imu_biases(const RealImu &real, const std::vector<ovton::core::StateSample> &gt,
                              const std::string &gt_name, double knot_dt_s) {
  RealImuBiases b;
  if (carries_biases(real.groundtruth)) {
    b.samples = real.groundtruth;
    b.source = "bias columns of the IMU source's ground truth";
  } else if (carries_biases(gt)) {
    b.samples = gt;
    b.source = "bias columns of " + gt_name;
  } else {
    ImuMatchOptions mo;
    mo.knot_dt_s = knot_dt_s;
    const ImuMatchReport m = match_imu(real.imu, gt, mo);
    b.bg = m.gyro_bias, b.ba = m.accel_bias;
    b.source = "constant, measured against " + gt_name + " (match_imu, " + std::to_string(m.samples) + " readings)";
  }
  return b;
}

} // namespace ovton::sim
