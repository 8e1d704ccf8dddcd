#include "tools/cli.h"
#include "ov_core/types/errors.h"

#include <iostream>

namespace ovton {

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
    throw ov_core::UsageError(std::string(option) + " must be on or off, not '" + value + "'");
  return value == "on";
}

} // namespace ovton
