#pragma once
// Reading an EuRoC folder for the OpenVINS peer programs (ov_euroc_harness.cpp, ov_track_exchange.cpp; built outside
// this repository against an OpenVINS source tree): CSV rows, the IMU log as OpenVINS's ImuData, a camera's image list.
// Errors end the program with a message naming the file (these are experiment tools, not the product).
#include "utils/quat_ops.h"
#include "utils/sensor_data.h"

#include <Eigen/Geometry>

#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace peer_io {

/// The rows of a CSV file, each split at commas; lines that do not start with a digit (headers, comments) are skipped.
inline std::vector<std::vector<std::string>> read_csv(const std::string &path) {
  std::ifstream f(path);
  if (!f) {
    std::cerr << "cannot open " << path << "\n";
    std::exit(2);
  }
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(f, line)) {
    if (!line.empty() && line.back() == '\r')
      line.pop_back();
    if (line.empty() || !std::isdigit(static_cast<unsigned char>(line[0])))
      continue;
    std::vector<std::string> cols;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ','))
      cols.push_back(c);
    rows.push_back(cols);
  }
  return rows;
}

/// mav0/imu0/data.csv as OpenVINS's IMU readings (seconds, rad/s, m/s²).
inline std::vector<ov_core::ImuData> load_imu(const std::string &mav0) {
  std::vector<ov_core::ImuData> imu;
  for (auto &r : read_csv(mav0 + "imu0/data.csv")) {
    ov_core::ImuData d;
    d.timestamp = std::stoll(r[0]) * 1e-9;
    d.wm << std::stod(r[1]), std::stod(r[2]), std::stod(r[3]);
    d.am << std::stod(r[4]), std::stod(r[5]), std::stod(r[6]);
    imu.push_back(d);
  }
  return imu;
}

struct Image {
  int64_t t; ///< camera stamp [ns]
  std::string path;
};

/// mav0/<cam>/data.csv: each image's stamp and file.
inline std::vector<Image> load_images(const std::string &mav0, const std::string &cam) {
  std::vector<Image> imgs;
  for (auto &r : read_csv(mav0 + cam + "/data.csv")) {
    std::string fn = r[1];
    while (!fn.empty() && fn.front() == ' ')
      fn.erase(fn.begin());
    imgs.push_back({std::stoll(r[0]), mav0 + cam + "/data/" + fn});
  }
  return imgs;
}

/// OpenVINS's IMU state (time, JPL q_GtoI, p, v, bg, ba) from mav0's ground truth at t_ns, interpolated linearly
/// (slerp for the attitude), for VioManager::initialize_with_gt; false when the ground truth does not bracket t_ns.
inline bool ground_truth_state(const std::string &mav0, int64_t t_ns, Eigen::Matrix<double, 17, 1> &state) {
  const auto gt = read_csv(mav0 + "state_groundtruth_estimate0/data.csv");
  size_t k = 0;
  while (k + 1 < gt.size() && std::stoll(gt[k + 1][0]) <= t_ns)
    k++;
  if (gt.empty() || std::stoll(gt[k][0]) > t_ns || k + 1 >= gt.size())
    return false;
  Eigen::Matrix<double, 16, 1> ga, gb;
  for (int i = 0; i < 16; i++)
    ga(i) = std::stod(gt[k][1 + i]), gb(i) = std::stod(gt[k + 1][1 + i]);
  const double u = double(t_ns - std::stoll(gt[k][0])) / double(std::stoll(gt[k + 1][0]) - std::stoll(gt[k][0]));
  const Eigen::Matrix<double, 16, 1> g = ga + u * (gb - ga);
  Eigen::Quaterniond qa(ga(3), ga(4), ga(5), ga(6)), qb(gb(3), gb(4), gb(5), gb(6));
  if (qa.dot(qb) < 0)
    qb.coeffs() *= -1;
  const Eigen::Quaterniond q_WB = qa.slerp(u, qb).normalized();
  state(0) = t_ns * 1e-9;
  state.block<4, 1>(1, 0) = ov_core::rot_2_quat(q_WB.toRotationMatrix().transpose()); // JPL q_GtoI
  state.block<3, 1>(5, 0) = g.segment<3>(0);                                          // p_IinG
  state.block<3, 1>(8, 0) = g.segment<3>(7);                                          // v_IinG
  state.block<3, 1>(11, 0) = g.segment<3>(10);                                        // bg
  state.block<3, 1>(14, 0) = g.segment<3>(13);                                        // ba
  return true;
}

} // namespace peer_io
