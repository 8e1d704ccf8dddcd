// The parts of bag support that need no ROS library: recognising a bag and choosing the reader.
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/types/errors.h"

#include <fstream>

namespace ovton::core {

bool is_rosbag_file(const std::string &path) {
  std::ifstream in(path, std::ios::binary);
  char magic[13] = {};
  return in.read(magic, 13) && std::string(magic, 13) == "#ROSBAG V2.0\n";
}

Dataset load_recording(const std::string &path, const BagOptions &opt) {
  if (is_rosbag_file(path) || (path.size() > 4 && path.compare(path.size() - 4, 4, ".bag") == 0))
    return load_bag(path, opt);
  if (!opt.calib.empty() || !opt.cam_topic.empty() || !opt.imu_topic.empty())
    throw UsageError("--calib, --cam-topic and --imu-topic apply to ROS bags only; " + path +
                     " is read as a dataset folder with its own calibration");
  return load_dataset(path);
}

} // namespace ovton::core
