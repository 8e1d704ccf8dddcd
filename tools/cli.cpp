#include "tools/cli.h"

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

} // namespace ovton
