#pragma once
// A dataset written as a ROS 1 bag (`ovton export`), as a ROS user's recording would hold it: mono8 sensor_msgs/Image
// (or a JPEG or PNG sensor_msgs/CompressedImage) on the camera topic, sensor_msgs/Imu on the IMU topic, header stamps
// from the dataset (camera clock for images, IMU clock for the IMU) and bag time equal to the header stamp.
#include "ov_core/io/dataset.h"

#include <cstdint>
#include <functional>
#include <string>

namespace ovton::core {

struct BagWriteOptions {
  std::string cam_topic = "/cam0/image_raw";
  std::string imu_topic = "/imu0";
  std::string compression = "none"; ///< none | bz2 | lz4 (rosbag's chunk compression)
  /// raw: mono8 sensor_msgs/Image on cam_topic; jpeg or png: sensor_msgs/CompressedImage on cam_topic/compressed
  std::string image_format = "raw";
  int jpeg_quality = 95;
  /// Also write Kalibr files beside the bag (camchain-imucam-STEM.yaml, imu-STEM.yaml: the names Kalibr gives them),
  /// which load_bag then finds on its own.
  bool kalibr_files = true;
};

struct BagWriteReport {
  size_t images = 0, imu = 0;
  uint64_t bytes = 0;
  std::string camchain_file, imu_file; ///< "" when not written
};

/// Writes `d` (a folder with images: a feature-level dataset has no pixels to write) to `out`. The bag is written as
/// OUT.partial and renamed when complete, so an interrupted export leaves no bag that looks whole. progress(i, n) is
/// called after each image; returning false stops (UsageError "interrupted").
BagWriteReport write_bag(const Dataset &d, const std::string &out, const BagWriteOptions &opt = {},
                         const std::function<bool(size_t, size_t)> &progress = {});

} // namespace ovton::core
