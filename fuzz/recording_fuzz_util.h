#pragma once
// Shared by the recording fuzzers (fuzz_mcap, fuzz_rosbag): a fixed calibration for 16x12 images (the seeds'
// size, fuzz/make_seeds.sh) and a load that reads every image the way a replay does.
#include "fuzz_util.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_store.h"

namespace ovfuzz {

/// An EuRoC-style calibration folder for the seeds' 16x12 camera, written once.
inline const std::string &calibration_folder() {
  static const std::string dir = [] {
    write_file("calib/mav0/cam0/sensor.yaml",
               "%YAML:1.0\nT_BS:\n  cols: 4\n  rows: 4\n  data: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\nrate_hz: 20\n"
               "resolution: [16, 12]\ncamera_model: pinhole\nintrinsics: [10, 10, 8, 6]\n"
               "distortion_model: radial-tangential\ndistortion_coefficients: [0, 0, 0, 0]\n");
    write_file("calib/mav0/imu0/sensor.yaml",
               "%YAML:1.0\nrate_hz: 200\ngyroscope_noise_density: 1.6968e-04\ngyroscope_random_walk: 1.9393e-05\n"
               "accelerometer_noise_density: 2.0000e-3\naccelerometer_random_walk: 3.0000e-3\n");
    return (scratch() / "calib").string();
  }();
  return dir;
}

/// Reads the raw images of a loaded recording (a compressed image would go to OpenCV's codecs, whose fuzzing is
/// OpenCV's), then the end a player reports (a cut file), and takes every image stamp to the IMU clock as the estimator
/// does.
inline void read_all(const ovton::core::Dataset &d) {
  if (d.notes.find(" compressed images)") == std::string::npos)
    for (const auto &e : d.images)
      ovton::core::load_image(e);
  for (double td : {0.0, 0.2, -0.2})
    for (const auto &e : d.images)
      (void)ovton::core::try_imu_time_ns(e.t_cam_ns, td);
  ovton::core::check_not_truncated(d);
}

} // namespace ovfuzz
