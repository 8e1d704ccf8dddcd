#pragma once
// Shared by the MCAP and ROS 2 recording tests (test_mcap*.cpp, test_ros2*.cpp): file bytes, the ovton binary, a
// short rendered flight, and the check that a recording reads back as the folder it was made from.
#include "io_test_util.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_store.h"
#include "ov_sim/simulator.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>

#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>

namespace ovtest {

inline std::string bytes_of(const std::string &file) {
  std::ifstream in(file, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline void write_bytes(const std::string &file, const std::string &b) {
  std::ofstream(file, std::ios::binary | std::ios::trunc).write(b.data(), static_cast<std::streamsize>(b.size()));
}

/// Runs a shell command, its stdout and stderr to `out`; returns the exit code.
inline int shell(const std::string &cmd, const std::string &out) {
  const int rc = std::system((cmd + " >" + out + " 2>&1").c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

/// The ovton binary built beside the test executable.
inline std::string ovton_binary() {
  return (std::filesystem::read_symlink("/proc/self/exe").parent_path() / "ovton").string();
}

/// A rendered flight (clean defaults) of `duration_s` in `dir`.
inline std::string render_flight(const std::string &dir, double duration_s, uint64_t seed) {
  ovton::sim::SimOptions o;
  o.out_dir = dir;
  o.duration_s = duration_s;
  o.seed = seed;
  ovton::sim::write_simulation(o);
  return dir;
}

/// A small EuRoC folder written in no time: `images` random smooth 64x48 gray PNGs (smooth: JPEG keeps them within a
/// grey level or two) at 20 Hz and a varying 200 Hz IMU log around them, for the tests that read recordings without
/// running the filter on them.
inline std::string small_folder(const std::string &dir, int images = 20, uint64_t seed = 1) {
  const std::string m = dir + "/mav0";
  std::string cam = kCamYaml;
  cam.replace(cam.find("[752, 480]"), 10, "[64, 48]");
  write_text(m + "/cam0/sensor.yaml", cam);
  write_text(m + "/imu0/sensor.yaml", kImuYaml);
  std::ostringstream list, imu;
  list << "#timestamp [ns],filename\n";
  cv::RNG rng(seed);
  std::filesystem::create_directories(m + "/cam0/data");
  for (int i = 0; i < images; ++i) {
    const int64_t t = 1050000000LL + 50000000LL * i;
    list << t << "," << t << ".png\n";
    cv::Mat coarse(6, 8, CV_8UC1), img;
    rng.fill(coarse, cv::RNG::UNIFORM, 0, 256);
    cv::resize(coarse, img, cv::Size(64, 48), 0, 0, cv::INTER_LINEAR);
    cv::imwrite(m + "/cam0/data/" + std::to_string(t) + ".png", img);
  }
  imu << "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
         "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
  imu.precision(17);
  for (int k = 0; k <= 10 * (images + 2); ++k)
    imu << 1000000000LL + 5000000LL * k << "," << 0.1 * std::sin(0.1 * k) << ",0.02," << 1e-3 * k << ",0.1,"
        << 0.2 * std::cos(0.05 * k) << ",9.81\n";
  write_text(m + "/cam0/data.csv", list.str());
  write_text(m + "/imu0/data.csv", imu.str());
  return dir;
}

/// `r` holds what `folder` holds: IMU readings exactly, image stamps exactly, every `stride`-th image's pixels exactly
/// (or within 2 grey levels on average, for a lossy compression).
inline void expect_like_folder(const ovton::core::Dataset &r, const ovton::core::Dataset &folder, bool exact_pixels,
                               size_t stride = 5) {
  ASSERT_EQ(r.images.size(), folder.images.size());
  ASSERT_EQ(r.imu.size(), folder.imu.size());
  for (size_t i = 0; i < r.imu.size(); ++i) {
    ASSERT_EQ(r.imu[i].t_imu_ns, folder.imu[i].t_imu_ns);
    ASSERT_EQ(r.imu[i].wm, folder.imu[i].wm);
    ASSERT_EQ(r.imu[i].am, folder.imu[i].am);
  }
  for (size_t i = 0; i < r.images.size(); i += stride) {
    ASSERT_EQ(r.images[i].t_cam_ns, folder.images[i].t_cam_ns);
    const cv::Mat x = ovton::core::load_image(r.images[i]), y = ovton::core::load_image(folder.images[i]);
    ASSERT_EQ(x.size(), y.size());
    if (exact_pixels)
      EXPECT_EQ(cv::countNonZero(x != y), 0) << "image " << i;
    else
      EXPECT_LT(cv::norm(x, y, cv::NORM_L1) / static_cast<double>(x.total()), 2.0) << "image " << i;
  }
}

} // namespace ovtest
