#include "tools/cli.h"
#include "ov_core/types/errors.h"

#include <iostream>

namespace ovton::cli {

bool parse_command_line(const Args &args, const boost::program_options::options_description &desc,
                        boost::program_options::variables_map &vm) {
  namespace po = boost::program_options;
  const po::parsed_options parsed = po::command_line_parser(args).options(desc).run();
  // No subcommand takes positional arguments, and boost drops them silently: a user's `ovton run ... KEY=VALUE` then
  // ran with the config unchanged and exited 0.
  for (const std::string &word : po::collect_unrecognized(parsed.options, po::include_positional)) {
    std::string msg = "unexpected argument '" + word + "': every argument is an option (--help lists them)";
    if (word.find('=') != std::string::npos && word.find('.') != std::string::npos)
      msg += "; config values are not set on the command line: put SECTION.KEY in a config file given with --config "
             "(scripts/config_override.py CONFIG OUT SECTION.KEY=VALUE writes one)";
    throw ovton::core::UsageError(msg);
  }
  po::store(parsed, vm);
  if (vm.count("help")) {
    std::cout << desc << "\n";
    return false;
  }
  boost::program_options::notify(vm);
  // Where a count limits the work, 0 or a negative number is a typo, not "no limit" (leave the option out for that).
  if (vm.count("max-images") && vm["max-images"].as<long>() < 1)
    throw ovton::core::UsageError("--max-images must be at least 1 (leave it out to process every image)");
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
