// `ovton compare`: run one dataset under several time-offset modes and write the paper's tables and figures.
#include "ov_core/io/csv.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/types/errors.h"
#include "ov_eval/metrics.h"
#include "tools/cli.h"
#include "tools/commands.h"
#include "tools/compare_report.h"
#include "tools/progress.h"
#include "tools/run_pipeline.h"

#include <algorithm>
#include <boost/program_options.hpp>
#include <filesystem>
#include <iostream>
#include <thread>

namespace po = boost::program_options;

namespace ovton::cli {

namespace {

/// The command as a user could paste it back into a shell (results.md says what produced it).
std::string shell_command(const Args &args) {
  std::string cmd = "ovton compare";
  for (const auto &a : args) {
    const bool plain =
        !a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-+=.,/:@%") ==
                          std::string::npos;
    if (plain) {
      cmd += " " + a;
      continue;
    }
    std::string q = " '";
    for (char c : a)
      q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    cmd += q + "'";
  }
  return cmd;
}

} // namespace

int cmd_compare(const Args &args) {
  po::options_description desc("ovton compare: run a dataset under several time-offset modes and compare them "
                               "(APE, ARE, TPE, CIT, runtime; t_d / APE / top-view plots)");
  std::string config, dataset, modes = "off,sr,sir,fvon,tpn,ton,oracle", init, align = "posyaw";
  CompareRequest req;
  desc.add_options()("help,h", "this help") //
      ("dataset,d", po::value(&dataset)->required(),
       "dataset folder (EuRoC, SCube or `ovton simulate` output), ROS 1 bag, MCAP file or rosbag2 folder")       //
      ("modes,m", po::value(&modes)->default_value(modes), "comma-separated time-offset modes to run")           //
      ("out,o", po::value(&req.out_dir)->required(), "results folder (created if needed)")                       //
      ("config,c", po::value(&config), "estimator config YAML shared by all modes (default: built-in defaults)") //
      ("init", po::value(&init), "static|groundtruth|auto|dynamic (overrides the config)")                       //
      ("jobs,j", po::value(&req.jobs)->default_value(2), "runs at a time")                                       //
      ("max-images", po::value(&req.max_images), "stop each run after this many images")                         //
      ("align", po::value(&align)->default_value(align), "trajectory alignment for APE/ARE: posyaw|se3");
  ovton::core::BagOptions bag_opt;
  add_bag_options(desc, bag_opt);
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm)) {
    std::cout << "Writes OUT/traj_<mode>.csv, OUT/results.md, OUT/results.csv, OUT/td.png, OUT/ape.png, OUT/top.png.\n"
              << "oracle is skipped when the dataset has no td_truth/data.csv.\n";
    return 0;
  }
  // Checked before the dataset is loaded, so that a typo costs nothing.
  req.modes = parse_compare_modes(modes);
  if (req.jobs < 1)
    throw ovton::core::UsageError("--jobs must be at least 1");
  if (align != "posyaw" && align != "se3" && align != "sim3")
    throw ovton::core::UsageError("--align must be posyaw, se3 or sim3");
  req.report.eval.align = ovton::eval::parse_align_mode(align);

  req.base = config.empty() ? ovton::msckf::VioOptions{} : ovton::msckf::load_vio_options(config);
  if (!init.empty())
    req.base.init.mode = ovton::msckf::parse_init_mode(init);
  req.info.command_line = shell_command(args);
  req.info.config = config;
  std::error_code ec;
  req.info.working_dir = std::filesystem::current_path(ec).string();
  req.log = &std::cerr;

  // The results folder is checked before the dataset is loaded and any mode runs.
  std::filesystem::create_directories(req.out_dir, ec);
  if (ec)
    throw ovton::core::DataError(req.out_dir, "cannot create the results folder: " + ec.message());
  ovton::core::require_writable((std::filesystem::path(req.out_dir) / "results.md").string());

  const ovton::core::Dataset data = ovton::core::load_recording(dataset, bag_opt);
  ovton::apply_dataset_defaults(data, false, req.base);
  for (const std::string &w : data.warnings)
    std::cerr << "compare: warning: " << w << "\n";
  std::cerr << "compare: " << req.modes.size() << " modes on " << data.root << " (" << data.images.size()
            << " images), " << std::min<size_t>(req.jobs, req.modes.size()) << " at a time on "
            << std::thread::hardware_concurrency() << " cores\n";

  install_interrupt_handler();
  const CompareResult res = run_compare(data, req);

  std::cout << ovton::eval::results_markdown_table(res.rows) << "\n";
  std::cout << "results: " << res.files.md << ", " << res.files.csv << "\n";
  if (res.interrupted) {
    std::cerr << "compare: interrupted; the report covers the runs that finished\n";
    return 130;
  }
  if (res.failed > 0) {
    std::cerr << "compare: " << res.failed << " of " << res.runs.size()
              << " modes failed (see the status column of results.md)\n";
    return 1;
  }
  return 0;
}

} // namespace ovton::cli
