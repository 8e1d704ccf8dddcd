// `ovton perturb`: the paper's EuRoC protocol — a real folder with image stamps rewritten by an offset model.
#include "ov_core/types/errors.h"
#include "ov_sim/perturb.h"
#include "tools/cli.h"
#include "tools/commands.h"

#include <boost/program_options.hpp>
#include <iostream>

namespace po = boost::program_options;

namespace ovton::cli {

int cmd_perturb(const Args &args) {
  po::options_description desc(
      "ovton perturb: copy a real EuRoC folder with cam0 stamps rewritten by a time-offset model\n"
      "(images are symlinked; the original stamps are taken as true IMU-clock times; t_imu = t_cam + td)");
  ovton::sim::PerturbOptions o;
  std::string td_model = "drift";
  double td0_ms = 10.0, td_bias = 0.1, td_noise = 0.1;
  desc.add_options()("help,h", "this help")                                                     //
      ("dataset,d", po::value(&o.in_dir)->required(), "input EuRoC folder")                     //
      ("out,o", po::value(&o.out_dir)->required(), "output folder (must not hold a mav0/ yet)") //
      ("seed", po::value(&o.seed)->default_value(1), "random seed")                             //
      ("td-model", po::value(&td_model)->default_value("drift"), "constant | drift")            //
      ("td0-ms", po::value(&td0_ms)->default_value(10.0), "offset at the first image [ms]")     //
      ("td-bias-ms-per-s", po::value(&td_bias)->default_value(0.1), "drift: growth [ms/s]")     //
      ("td-noise-ms-per-sqrt-s", po::value(&td_noise)->default_value(0.1), "drift: random walk [ms/sqrt(s)]");
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0; // --help
  o.td.kind = ovton::sim::parse_td_model(td_model);
  o.td.td0_s = td0_ms * 1e-3;
  o.td.bias_s_per_s = td_bias * 1e-3;
  o.td.noise_s_per_sqrt_s = td_noise * 1e-3;
  const auto rep = ovton::sim::perturb_dataset(o);
  std::cout << "wrote " << o.out_dir << ": " << rep.n_images << " images restamped, td " << rep.td_first_s * 1e3
            << " ms -> " << rep.td_last_s * 1e3 << " ms\n";
  return 0;
}

} // namespace ovton::cli
