// `ovton eval`: APE/ARE/RPE/TPE/CIT of a trajectory against ground truth (paper §V-A).
#include "ov_core/io/text_format.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/types/errors.h"
#include "ov_eval/metrics.h"
#include "tools/cli.h"
#include "tools/commands.h"

#include <boost/program_options.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace po = boost::program_options;

namespace {

std::vector<double> parse_segments(const std::string &s) {
  std::vector<double> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item.empty())
      continue;
    std::size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception &) {
      used = 0;
    }
    if (used != item.size() || !(v > 0.0) || !std::isfinite(v))
      throw ovton::core::UsageError("--rpe-segments: '" + item + "' is not a positive length in metres");
    out.push_back(v);
  }
  return out;
}

std::ofstream open_out(const std::string &file) {
  std::ofstream out(file);
  if (!out)
    throw ovton::core::DataError(file, "cannot open for writing");
  return out;
}

void close_out(std::ofstream &out, const std::string &file) {
  out.close();
  if (!out)
    throw ovton::core::DataError(file, "write failed");
}

} // namespace

int ovton::cli::cmd_eval(const ovton::cli::Args &args) {
  std::string est_file, gt_file, align_str, td_file, json_file, csv_file, seg_str;
  double eps1_ms = 1.0, eps2_ms = 0.1, max_gap_s = 0.1;
  po::options_description desc(
      "usage: ovton eval --est FILE --gt FILE [options]\n\n"
      "Compares an estimated trajectory (project CSV, EuRoC CSV or TUM text) with ground truth\n"
      "(same formats, or position-only `timestamp_ns,px,py,pz`), interpolated at the estimate's\n"
      "stamps. TPE and CIT need the estimate's td column and, for TPE, --td-truth.\n\noptions");
  // clang-format off
  desc.add_options()
    ("help,h", "print this help")
    ("est", po::value(&est_file), "estimated trajectory (IMU clock)")
    ("gt", po::value(&gt_file), "ground-truth trajectory (IMU clock)")
    ("align", po::value(&align_str)->default_value("posyaw"),
     "alignment before APE/ARE: posyaw (4-DOF, the VIO convention), se3, sim3 (also reports the scale), none")
    ("td-truth", po::value(&td_file), "true time offset per image, `timestamp_ns,td_s` (camera clock)")
    ("eps1-ms", po::value(&eps1_ms)->default_value(1.0, "1"), "CIT: |td - target| threshold [ms]")
    ("eps2-ms", po::value(&eps2_ms)->default_value(0.1, "0.1"), "CIT: |td(k) - td(k-1)| threshold [ms]")
    ("cit-target-ms", po::value<double>(), "CIT target [ms] (default: the --td-truth value at each frame)")
    ("rpe-segments", po::value(&seg_str)->default_value("1,2,4,8,16"),
     "RPE segment lengths along the ground-truth path [m], comma separated")
    ("max-gap-s", po::value(&max_gap_s)->default_value(0.1, "0.1"),
     "drop estimates that fall in a ground-truth gap longer than this [s]")
    ("json", po::value(&json_file), "also write the results as JSON")
    ("csv", po::value(&csv_file), "also write the results as a one-row CSV with header");
  // clang-format on
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0; // --help
  if (est_file.empty() || gt_file.empty())
    throw ovton::core::UsageError("--est and --gt are required (see ovton eval --help)");
  if (!(eps1_ms > 0.0) || !(eps2_ms > 0.0))
    throw ovton::core::UsageError("--eps1-ms and --eps2-ms must be positive");
  if (!(max_gap_s > 0.0))
    throw ovton::core::UsageError("--max-gap-s must be positive");

  ovton::eval::EvalOptions opt;
  opt.align = ovton::eval::parse_align_mode(align_str);
  opt.rpe_segments_m = parse_segments(seg_str);
  opt.max_gap_s = max_gap_s;
  opt.cit.eps1_s = eps1_ms * 1e-3;
  opt.cit.eps2_s = eps2_ms * 1e-3;
  if (vm.count("cit-target-ms")) {
    opt.cit.target_from_truth = false;
    opt.cit.target_s = vm["cit-target-ms"].as<double>() * 1e-3;
  }

  const auto est = ovton::core::read_trajectory(est_file);
  const auto gt = ovton::core::read_trajectory(gt_file);
  std::vector<ovton::core::TdSample> td_truth;
  if (!td_file.empty())
    td_truth = ovton::core::read_td_truth(td_file);
  const ovton::eval::EvalResult r = ovton::eval::evaluate(est, gt, td_truth, opt);

  const double yaw_deg = std::atan2(r.alignment.R(1, 0), r.alignment.R(0, 0)) * 180.0 / M_PI;
  std::ostream &os = std::cout;
  os << "estimate     " << est_file << "  (" << r.n_est << " poses)\n"
     << "ground truth " << gt_file << "  (" << gt.size() << " poses)\n"
     << "matched      " << r.n_matched << " of " << r.n_est << " estimates\n"
     << "alignment    " << ovton::eval::to_string(r.align_mode) << "  (t = ["
     << ovton::core::format_fixed(r.alignment.t.x(), 3) << ", " << ovton::core::format_fixed(r.alignment.t.y(), 3)
     << ", " << ovton::core::format_fixed(r.alignment.t.z(), 3) << "] m, yaw " << ovton::core::format_fixed(yaw_deg, 2)
     << " deg";
  if (r.align_mode == ovton::eval::AlignMode::Sim3)
    os << ", scale " << ovton::core::format_fixed(r.alignment.s, 4) << ": estimate "
       << ovton::core::format_fixed(100.0 * (1.0 / r.alignment.s - 1.0), 2) << " % too large";
  os << ")\n\n";
  os << "metric                 value\n"
     << "APE RMSE [m]           " << ovton::core::format_fixed(r.ape_rmse_m, 4) << "\n"
     << "APE mean [m]           " << ovton::core::format_fixed(r.ape_mean_m, 4) << "\n"
     << "APE max  [m]           " << ovton::core::format_fixed(r.ape_max_m, 4) << "\n"
     << "ARE RMSE [deg]         " << ovton::core::format_fixed(r.are_rmse_deg, 3)
     << (std::isnan(r.are_rmse_deg) ? "   (ground truth has no orientation)" : "") << "\n"
     << "TPE RMSE [mm]          "
     << (r.has_tpe ? ovton::core::format_fixed(r.tpe_rmse_mm, 3) : std::string("n/a (needs td column and --td-truth)"))
     << "\n"
     << "t_d err RMSE [ms]      "
     << (r.has_tpe ? ovton::core::format_fixed(r.td_err_rmse_ms, 3) + "  (second half " +
                         ovton::core::format_fixed(r.td_err_rmse_late_ms, 3) + ")"
                   : std::string("n/a"))
     << "\n"
     << "t_d NEES               " << (r.has_tpe ? ovton::core::format_fixed(r.td_nees, 3) : std::string("n/a"))
     << (r.has_tpe ? "   (1 is ideal)" : "") << "\n"
     << "CIT [frame]            "
     << (r.has_cit ? (r.cit >= 0 ? std::to_string(r.cit) : std::string("never converged"))
                   : std::string("n/a (needs td column and --td-truth or --cit-target-ms)"))
     << "\n\n";
  os << "RPE segment [m]   count   trans RMSE [m]   rot RMSE [deg]\n";
  for (const auto &rr : r.rpe)
    os << std::setw(15) << ovton::core::format_fixed(rr.segment_m, 1) << std::setw(8) << rr.count << std::setw(17)
       << ovton::core::format_fixed(rr.trans_rmse_m, 4) << std::setw(17)
       << ovton::core::format_fixed(rr.rot_rmse_deg, 3) << "\n";

  if (!json_file.empty()) {
    std::ofstream out = open_out(json_file);
    out << "{\n  \"est\": " << ovton::core::json_string(est_file)
        << ",\n  \"gt\": " << ovton::core::json_string(gt_file)
        << ",\n  \"align\": " << ovton::core::json_string(ovton::eval::to_string(r.align_mode))
        << ",\n  \"align_scale\": " << ovton::core::json_number(r.alignment.s) << ",\n  \"n_est\": " << r.n_est
        << ",\n  \"n_matched\": " << r.n_matched << ",\n  \"ape_rmse_m\": " << ovton::core::json_number(r.ape_rmse_m)
        << ",\n  \"ape_mean_m\": " << ovton::core::json_number(r.ape_mean_m)
        << ",\n  \"ape_max_m\": " << ovton::core::json_number(r.ape_max_m)
        << ",\n  \"are_rmse_deg\": " << ovton::core::json_number(r.are_rmse_deg)
        << ",\n  \"tpe_rmse_mm\": " << (r.has_tpe ? ovton::core::json_number(r.tpe_rmse_mm) : "null")
        << ",\n  \"td_err_rmse_ms\": " << (r.has_tpe ? ovton::core::json_number(r.td_err_rmse_ms) : "null")
        << ",\n  \"td_err_rmse_late_ms\": " << (r.has_tpe ? ovton::core::json_number(r.td_err_rmse_late_ms) : "null")
        << ",\n  \"td_nees\": " << (r.has_tpe ? ovton::core::json_number(r.td_nees) : "null")
        << ",\n  \"cit\": " << (r.has_cit ? std::to_string(r.cit) : "null") << ",\n  \"rpe\": [";
    for (size_t i = 0; i < r.rpe.size(); ++i)
      out << (i ? "," : "") << "\n    {\"segment_m\": " << ovton::core::json_number(r.rpe[i].segment_m)
          << ", \"count\": " << r.rpe[i].count
          << ", \"trans_rmse_m\": " << ovton::core::json_number(r.rpe[i].trans_rmse_m)
          << ", \"rot_rmse_deg\": " << ovton::core::json_number(r.rpe[i].rot_rmse_deg) << "}";
    out << "\n  ]\n}\n";
    close_out(out, json_file);
  }
  if (!csv_file.empty()) {
    std::ofstream out = open_out(csv_file);
    out << "align,n_est,n_matched,ape_rmse_m,ape_mean_m,ape_max_m,are_rmse_deg,tpe_rmse_mm,cit,td_err_rmse_ms,"
           "td_err_rmse_late_ms,td_nees";
    for (const auto &rr : r.rpe)
      out << ",rpe_" << ovton::core::json_number(rr.segment_m) << "m_trans_rmse_m,rpe_"
          << ovton::core::json_number(rr.segment_m) << "m_rot_rmse_deg";
    out << "\n"
        << ovton::eval::to_string(r.align_mode) << "," << r.n_est << "," << r.n_matched << ","
        << ovton::core::csv_number(r.ape_rmse_m) << "," << ovton::core::csv_number(r.ape_mean_m) << ","
        << ovton::core::csv_number(r.ape_max_m) << "," << ovton::core::csv_number(r.are_rmse_deg) << ","
        << (r.has_tpe ? ovton::core::csv_number(r.tpe_rmse_mm) : "") << "," << (r.has_cit ? std::to_string(r.cit) : "")
        << "," << (r.has_tpe ? ovton::core::csv_number(r.td_err_rmse_ms) : "") << ","
        << (r.has_tpe ? ovton::core::csv_number(r.td_err_rmse_late_ms) : "") << ","
        << (r.has_tpe ? ovton::core::csv_number(r.td_nees) : "");
    for (const auto &rr : r.rpe)
      out << "," << ovton::core::csv_number(rr.trans_rmse_m) << "," << ovton::core::csv_number(rr.rot_rmse_deg);
    out << "\n";
    close_out(out, csv_file);
  }
  return 0;
}
