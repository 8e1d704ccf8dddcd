#pragma once
// ROS 2 recordings replayed without ROS: MCAP files and rosbag2 folders (metadata.yaml with .mcap or .db3 files,
// split files in order), carrying sensor_msgs/msg/Image (mono8, mono16, bgr8, rgb8, bgra8, rgba8) or CompressedImage
// (JPEG, PNG) and sensor_msgs/msg/Imu in CDR. As for ROS 1 bags (rosbag_reader.h): the header stamp is the sensor's
// time, the IMU log is read at load, each image only when the replay reaches it. Calibration: --calib, files beside
// the recording (bag_calibration.h), else the recording's own CameraInfo and /tf_static.
#include "ov_core/io/dataset.h"
#include "ov_core/io/rosbag_reader.h"

#include <string>

namespace ovton::core {

/// True when `path` is a regular file that starts with the MCAP magic.
bool is_mcap_file(const std::string &path);
/// True when `path` is a folder holding a rosbag2 metadata.yaml.
bool is_ros2_bag_folder(const std::string &path);

/// Loads an MCAP file (kind "mcap"). Throws DataError naming the file and the byte offset or the message for a damaged
/// file (a chunk whose CRC fails, a malformed record), an unknown message encoding, a missing, ambiguous or empty
/// topic, an unsupported image encoding or a size other than the calibration's. A file cut short (no Data End record: a
/// recorder that crashed) is read up to the last complete record and marked so (Dataset::truncated_file).
Dataset load_mcap(const std::string &file, const BagOptions &opt = {});
/// Loads a rosbag2 folder (kind "ros2bag"): storage mcap or sqlite3, its files in metadata.yaml's order.
Dataset load_ros2_bag(const std::string &folder, const BagOptions &opt = {});

} // namespace ovton::core
