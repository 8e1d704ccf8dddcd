#pragma once
// Flag parsing shared by every subcommand.
#include "ov_core/io/rosbag_reader.h"
#include "tools/commands.h"

#include <boost/program_options.hpp>
#include <string>

namespace ovton::cli {

/// Parses args into vm; on --help prints `desc` to stdout and returns false (the command then exits with 0).
/// Missing required options and malformed values throw boost::program_options::error (main() reports them).
bool parse_command_line(const Args &args, const boost::program_options::options_description &desc,
                        boost::program_options::variables_map &vm);

/// "on" -> true, "off" -> false; anything else is a UsageError naming the option.
bool parse_on_off(const std::string &value, const char *option);
/// --cam-topic, --imu-topic and --calib, for the commands that read a dataset folder or a ROS bag.
void add_bag_options(boost::program_options::options_description &desc, ovton::core::BagOptions &opt);

} // namespace ovton::cli
