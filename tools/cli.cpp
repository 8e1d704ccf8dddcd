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
                     "ROS bag: sensor_msgs/Image topic (default: the only one, the calibration's rostopic, or "
                     "/cam0/image_raw)") //
      ("imu-topic", boost::program_options::value(&opt.imu_topic),
       "ROS bag: sensor_msgs/Imu topic (default: the only one, the calibration's rostopic, or /imu0)") //
      ("calib", boost::program_options::value(&opt.calib)->multitoken(),
       "ROS bag: Kalibr camchain and imu YAML, or an EuRoC folder (default: found beside the bag: BAG/ folder, "
       "camchain-imucam-BAG.yaml + imu-BAG.yaml, camchain-imucam.yaml + imu.yaml)");
}

} // namespace ovton::cli
