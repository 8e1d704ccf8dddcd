#pragma once
// `ovton compare` as a function: one estimator run per time-offset mode on a dataset loaded once, then the report
// (ov_eval/report.h). Kept apart from the flag parsing so that a `protocol` command can call it per dataset.
#include "ov_core/io/dataset.h"
#include "ov_eval/report.h"
#include "ov_msckf_ton/core/vio_options.h"

#include <iosfwd>
#include <string>
#include <vector>

namespace ovton::cli {

struct CompareRequest {
  std::vector<ovton::msckf::ModeSpec> modes;
  ovton::msckf::VioOptions base; ///< shared by every run; the mode (and process) is set per run
  std::string out_dir;           ///< traj_<mode>.csv, results.md, results.csv, td.png, ape.png, top.png
  int jobs = 2;                  ///< runs at a time, each on its own thread with its own VioManager
  long max_images = 0;           ///< 0 = all
  ovton::eval::ReportOptions report;
  ovton::eval::ReportInfo info; ///< command line and config for results.md; jobs is filled in from above
  std::ostream *log = nullptr;  ///< one line per finished mode; nullptr = silent
};

struct CompareResult {
  std::vector<ovton::eval::RunRecord> runs; ///< in the order of the requested modes, skipped ones included
  std::vector<ovton::eval::ReportRow> rows;
  ovton::eval::ReportFiles files;
  int failed = 0;           ///< runs whose status is "failed: ..."
  bool interrupted = false; ///< SIGINT stopped the comparison; the report covers what was done
};

/// "off,sr,sr+random_walk,oracle" -> mode specs (MODE[+PROCESS]), in that order. Throws UsageError naming an
/// unknown or repeated entry.
std::vector<ovton::msckf::ModeSpec> parse_compare_modes(const std::string &list);

/// Runs every mode and writes the report. Modes the dataset cannot support (oracle without td_truth) are skipped
/// with a row that says why. A failing run is reported in its row and does not stop the others. Throws UsageError
/// for a request no mode could satisfy (ground-truth initialisation without full-state ground truth).
CompareResult run_compare(const ovton::core::Dataset &data, const CompareRequest &req);

} // namespace ovton::cli
