#pragma once
// Reading an EuRoC folder for the OpenVINS peer programs (ov_euroc_harness.cpp, ov_track_exchange.cpp; built outside
// this repository against an OpenVINS source tree): CSV rows, the IMU log as OpenVINS's ImuData, a camera's image list.
// Errors end the program with a message naming the file (these are experiment tools, not the product).
#include "utils/sensor_data.h"

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

} // namespace peer_io
