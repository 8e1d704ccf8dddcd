// ovton: the command-line front of ov_msckf_ton. Only this file turns exceptions into exit codes: 2 usage, 3 data
// (file and line), 4 a diverged estimate (filter_health.h), 130 interrupted; 1 anything else.
#include "ov_core/types/errors.h"
#include "tools/commands.h"

#include <boost/program_options/errors.hpp>
#include <functional>
#include <iostream>
#include <map>

namespace {

struct Command {
  std::function<int(const ovton::cli::Args &)> run;
  const char *help;
};

const std::map<std::string, Command> &commands() {
  static const std::map<std::string, Command> cmds = {
      {"run", {ovton::cli::cmd_run, "replay a dataset through the MSCKF and write a trajectory CSV"}},
      {"compare", {ovton::cli::cmd_compare, "run a dataset under several time-offset modes: tables and plots"}},
      {"calibrate",
       {ovton::cli::cmd_calibrate, "estimate camera-IMU rotation, focal, t_d, readout of a recording without them"}},
      {"info", {ovton::cli::cmd_info, "load a dataset folder, validate it and print what it holds"}},
      {"eval", {ovton::cli::cmd_eval, "APE/ARE/RPE/TPE/CIT of a trajectory against ground truth"}},
      {"simulate", {ovton::cli::cmd_simulate, "write a synthetic EuRoC-format folder with a known time offset"}},
      {"export",
       {ovton::cli::cmd_export, "write a dataset or recording as a ROS 1 bag or an MCAP file (+ Kalibr files)"}},
      {"perturb", {ovton::cli::cmd_perturb, "rewrite a real folder's image stamps with a time-offset model"}},
      {"benchmark", {ovton::cli::cmd_benchmark, "per-frame cost by stage, x real time and memory, mode by mode"}},
      {"diagnose", {ovton::cli::cmd_diagnose, "rank candidate effects behind the residuals of `run --residual-log`"}},
      {"track", {ovton::cli::cmd_track, "the KLT front end alone: tracks as features.csv, scored against the truth"}},
      {"velocities",
       {ovton::cli::cmd_velocities, "score the image velocities of `run --velocity-log` against the truth"}},
      {"trackstats",
       {ovton::cli::cmd_trackstats, "how long a KLT keeps features on a folder's images; gradients, noise"}},
  };
  return cmds;
}

void usage(std::ostream &os) {
  os << "usage: ovton <command> [options]   (ovton <command> --help for its options)\n\ncommands:\n";
  for (const auto &[name, c] : commands())
    os << "  " << name << std::string(12 - name.size(), ' ') << c.help << "\n";
}

} // namespace

int main(int argc, char **argv) {
  if (argc < 2) {
    usage(std::cerr);
    return 2;
  }
  const std::string name = argv[1];
  if (name == "-h" || name == "--help" || name == "help") {
    usage(std::cout);
    return 0;
  }
  auto it = commands().find(name);
  if (it == commands().end()) {
    std::cerr << "ovton: unknown command '" << name << "'\n";
    usage(std::cerr);
    return 2;
  }
  ovton::cli::Args args(argv + 2, argv + argc);
  try {
    return it->second.run(args);
  } catch (const ovton::core::DataError &e) {
    std::cerr << "ovton " << name << ": data error: " << e.what() << "\n";
    return 3;
  } catch (const ovton::core::EstimatorFailure &e) {
    std::cerr << "ovton " << name << ": estimate failed: " << e.what() << "\n";
    return 4;
  } catch (const ovton::core::UsageError &e) {
    std::cerr << "ovton " << name << ": " << e.what() << "\n";
    return 2;
  } catch (const boost::program_options::error &e) {
    std::cerr << "ovton " << name << ": " << e.what() << "\n";
    return 2;
  } catch (const std::exception &e) {
    std::cerr << "ovton " << name << ": error: " << e.what() << "\n";
    return 1;
  }
}
