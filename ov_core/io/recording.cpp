// The parts of bag support that need no ROS library: recognising a recording and choosing the reader.
#include "ov_core/io/ros2_reader.h"
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/types/errors.h"

#include <fstream>

namespace ovton::core {

bool is_rosbag_file(const std::string &path) {
  std::ifstream in(path, std::ios::binary);
  char magic[13] = {};
  return in.read(magic, 13) && std::string(magic, 13) == "#ROSBAG V2.0\n";
}

namespace {
bool ends_with(const std::string &s, const char *tail) {
  const std::string t(tail);
  return s.size() > t.size() && s.compare(s.size() - t.size(), t.size(), t) == 0;
}
} // namespace

Dataset load_recording(const std::string &path, const BagOptions &opt) {
  if (is_rosbag_file(path) || ends_with(path, ".bag"))
    return load_bag(path, opt);
  if (is_mcap_file(path) || ends_with(path, ".mcap"))
    return load_mcap(path, opt);
  if (is_ros2_bag_folder(path))
    return load_ros2_bag(path, opt);
  if (!opt.calib.empty() || !opt.cam_topic.empty() || !opt.imu_topic.empty())
    throw UsageError("--calib, --cam-topic and --imu-topic apply to ROS bags and MCAP files only; " + path +
                     " is read as a dataset folder with its own calibration");
  return load_dataset(path);
}

} // namespace ovton::core
