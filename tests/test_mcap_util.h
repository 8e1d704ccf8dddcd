#pragma once
// Shared by the MCAP and ROS 2 recording tests (test_mcap*.cpp, test_ros2*.cpp): file bytes, the ovton binary, a
// short rendered flight, and the check that a recording reads back as the folder it was made from.
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_store.h"
#include "ov_sim/simulator.h"
#include "test_util.h"

#include <gtest/gtest.h>

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
