#pragma once
// ROS 1 bags replayed without ROS: sensor_msgs/Image or CompressedImage and sensor_msgs/Imu read with Debian's rosbag
// storage library (no master, no catkin workspace). The IMU log is read at load; images stay in the bag and are read
// one at a time when the replay reaches them (ImageEntry::store), so memory does not grow with the bag.
#include "ov_core/io/dataset.h"

#include <string>
#include <vector>

namespace ovton::core {

struct BagOptions {
  std::string
      cam_topic; ///< "" = the calibration's rostopic, /cam0/image_raw, or the only Image or CompressedImage topic
  std::string imu_topic; ///< "" = the calibration's rostopic, /imu0, or the only sensor_msgs/Imu topic
  /// Calibration: Kalibr camchain and imu YAML files, or a folder (EuRoC with mav0/, or Kalibr files). Empty: looked
  /// for beside the bag (bag_calibration.h).
  std::vector<std::string> calib;
};

/// False when ovton was built without the rosbag storage library (OVTON_WITH_ROSBAG=OFF): load_bag and write_bag then
/// throw UsageError saying so.
bool rosbag_supported();

/// True when `path` is a regular file that starts with the ROS 1 bag magic ("#ROSBAG V2.0").
bool is_rosbag_file(const std::string &path);

/// Loads a bag as a Dataset (kind "rosbag"): images by header stamp from the camera topic (sensor_msgs/Image mono8,
/// mono16, bgr8, rgb8, bgra8, rgba8, or sensor_msgs/CompressedImage JPEG or PNG; converted to 8-bit gray when read),
/// IMU readings from the IMU topic, calibration and any ground truth as bag_calibration.h finds them. Throws DataError
/// naming the bag and the message index (its position in the bag's time order, from 0) for a corrupt, truncated or
/// unindexed bag, a missing or ambiguous topic, an unsupported encoding, an image of another size than the
/// calibration's, duplicate stamps or an IMU gap.
Dataset load_bag(const std::string &file, const BagOptions &opt = {});

/// A dataset folder (load_dataset), a ROS 1 bag (load_bag), an MCAP file (load_mcap) or a rosbag2 folder
/// (load_ros2_bag, ros2_reader.h), whichever `path` is. For a dataset folder, BagOptions must be empty (a folder
/// carries its own calibration).
Dataset load_recording(const std::string &path, const BagOptions &opt = {});

} // namespace ovton::core
