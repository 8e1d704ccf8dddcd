#include "tools/cli.h"
#include "ov_core/types/errors.h"

#include <iostream>

namespace ovton::cli {

bool parse_command_line(const Args &args, const boost::program_options::options_description &desc,
                        boost::program_options::variables_map &vm) {
  boost::program_options::store(boost::program_options::command_line_parser(args).options(desc).run(), vm);
  if (vm.count("help")) {
    std::cout << desc << "\n";
    return false;
  }
  boost::program_options::notify(vm);
  return true;
}

bool parse_on_off(const std::string &value, const char *option) {
  if (value != "on" && value != "off")
    throw ovton::core::UsageError(std::string(option) + " must be on or off, not '" + value + "'");
  return value == "on";
}

void add_bag_options(boost::program_options::options_description &desc, ovton::core::BagOptions &opt) {
  desc.add_options()("cam-topic", boost::program_options::value(&opt.cam_topic),
                     "ROS bag or MCAP: image topic, Image or CompressedImage (default: the calibration's "
                     "rostopic, /cam0/image_raw, or the only one)") //
      ("imu-topic", boost::program_options::value(&opt.imu_topic),
       "ROS bag or MCAP: sensor_msgs/Imu topic (default: the calibration's rostopic, /imu0, or the only one)") //
      ("calib", boost::program_options::value(&opt.calib)->multitoken(),
       "ROS bag or MCAP: Kalibr camchain and imu YAML, or an EuRoC folder (default: found beside the recording: "
       "STEM/ folder, camchain-imucam-STEM.yaml + imu-STEM.yaml, camchain-imucam.yaml + imu.yaml; else a ROS 2 "
       "recording's CameraInfo and /tf_static)");
}

} // namespace ovton::cli
