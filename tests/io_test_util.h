#pragma once
// Small datasets and line editing, shared by the reader and robustness tests (test_io*.cpp, test_cli_robustness.cpp,
// test_filter_health.cpp, test_td_search.cpp).
#include "ov_sim/simulator.h"
#include "test_util.h"

#include <cstdint>
#include <sstream>
#include <string>

namespace ovtest {

inline const char *kCamYaml = R"(%YAML:1.0
sensor_type: camera
T_BS:
  cols: 4
  rows: 4
  data: [0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,
        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 20
resolution: [752, 480]
camera_model: pinhole
intrinsics: [458.654, 457.296, 367.215, 248.375]
distortion_model: radial-tangential
distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]
)";

inline const char *kImuYaml = R"(%YAML:1.0
sensor_type: imu
rate_hz: 200
gyroscope_noise_density: 1.6968e-04
gyroscope_random_walk: 1.9393e-05
accelerometer_noise_density: 2.0000e-3
accelerometer_random_walk: 3.0000e-3
)";

/// A small valid EuRoC folder: 5 images at 20 Hz, 1 s of IMU at 200 Hz, ground truth. Returns the root.
inline std::string make_euroc(const TempDir &tmp) {
  const std::string m = tmp / "mav0";
  write_text(m + "/cam0/sensor.yaml", kCamYaml);
  write_text(m + "/imu0/sensor.yaml", kImuYaml);
  std::ostringstream cam, imu, gt;
  cam << "#timestamp [ns],filename\n";
  for (int i = 0; i < 5; ++i) {
    const int64_t t = 1000000000LL + 50000000LL * (i + 1);
    cam << t << "," << t << ".png\n";
    write_text(m + "/cam0/data/" + std::to_string(t) + ".png", "not decoded by the reader");
  }
  imu << "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
         "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
  for (int i = 0; i <= 200; ++i)
    imu << 1000000000LL + 5000000LL * i << ",0.01,0.02,0.03,0.1,0.2,9.81\n";
  gt << "#time(ns),px,py,pz,qw,qx,qy,qz,vx,vy,vz,bwx,bwy,bwz,bax,bay,baz\n";
  for (int i = 0; i <= 20; ++i)
    gt << 1000000000LL + 50000000LL * i << "," << 0.1 * i << ",0,1,1,0,0,0,2,0,0,0,0,0,0,0,0\n";
  write_text(m + "/cam0/data.csv", cam.str());
  write_text(m + "/imu0/data.csv", imu.str());
  write_text(m + "/state_groundtruth_estimate0/data.csv", gt.str());
  return tmp.str();
}

inline void replace_line(const std::string &file, int line_no, const std::string &new_line) {
  std::istringstream in(ovtest::read_text(file));
  std::ostringstream out;
  std::string l;
  for (int i = 1; std::getline(in, l); ++i)
    out << (i == line_no ? new_line : l) << "\n";
  write_text(file, out.str());
}

/// Options of a feature-level simulation (no images: written and run in about a second) of the built-in flight with
/// ov_sim's default +10 ms offset; the caller may change more before ovton::sim::write_simulation.
inline ovton::sim::SimOptions feature_sim(const std::string &out_dir, double duration_s, uint64_t seed) {
  ovton::sim::SimOptions o;
  o.out_dir = out_dir;
  o.duration_s = duration_s;
  o.seed = seed;
  o.features_only = true;
  return o;
}

} // namespace ovtest
