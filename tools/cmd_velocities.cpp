// `ovton velocities`: scores the image velocities of a velocity log (`ovton run --velocity-log`) against the truth.
#include "ov_core/io/dataset.h"
#include "ov_core/types/errors.h"
#include "ov_eval/velocity_truth.h"
#include "tools/cli.h"
#include "tools/commands.h"

#include <boost/program_options.hpp>
#include <fstream>
#include <iostream>

namespace po = boost::program_options;

int ovton::cli::cmd_velocities(const ovton::cli::Args &args) {
  std::string log_file, dataset_dir, md_file;
  ovton::eval::VelocityEvalOptions opt;
  po::options_description desc(
      "usage: ovton velocities --log FILE --dataset DIR [--md FILE]\n\n"
      "Scores every image velocity in a velocity log (ovton run --velocity-log; in modes fvon/ton both networks\n"
      "predict every new feature) against the truth: each track is triangulated from the dataset's ground-truth\n"
      "poses and its true velocity is the derivative of that point's projection along the true motion. Prints\n"
      "RMS and median errors per rule (paper eq. 2 on tracked observations; next, ITS-FVON, F2F-FVON on first\n"
      "observations) and the share within the filter's FVON gate.\n\noptions");
  // clang-format off
  desc.add_options()
    ("help,h", "print this help")
    ("log", po::value(&log_file), "velocity log CSV (ovton run --velocity-log)")
    ("dataset", po::value(&dataset_dir), "the dataset folder the log was made from (needs full-pose ground truth)")
    ("md", po::value(&md_file), "also write the table to this Markdown file")
    ("gate", po::value(&opt.gate_px_s)->default_value(opt.gate_px_s), "error threshold for the 'within gate' column [px/s]")
    ("max-reproj-px", po::value(&opt.max_reproj_px)->default_value(opt.max_reproj_px),
     "tracks reprojecting worse than this from the true poses are left out [px]");
  // clang-format on
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0; // --help
  if (log_file.empty() || dataset_dir.empty())
    throw ovton::core::UsageError("--log and --dataset are required (see ovton velocities --help)");
  ovton::core::LoadOptions lo;
  lo.check_images_exist = false;
  const ovton::core::Dataset data = ovton::core::load_dataset(dataset_dir, lo);
  const auto rows = ovton::core::read_velocity_log(log_file);
  const ovton::eval::VelocityEvalResult r = ovton::eval::evaluate_velocities(rows, data, opt);
  const std::string table = ovton::eval::velocity_table(r);
  std::cout << table;
  if (!md_file.empty()) {
    std::ofstream out(md_file);
    out << table;
    if (!out)
      throw ovton::core::DataError(md_file, "cannot write");
  }
  return 0;
}
