#pragma once
// Side-by-side reports of several estimator runs on one dataset (`ovton compare`, later `protocol`): the table of
// paper §V-A metrics as Markdown + CSV and the three figures (t_d over time, APE over time, top view).
// Nothing here knows the estimator: a run arrives as a trajectory plus timings, named by the caller, so the same
// code serves any set of configurations.
#include "ov_core/io/dataset.h"
#include "ov_core/types/sensor_data.h"
#include "ov_eval/metrics.h"

#include <functional>
#include <string>
#include <vector>

namespace ovton::eval {

/// Writes `text` beside `file` and renames it into place, so that a reader (or an interrupted run) never sees half a
/// file. Throws DataError when it cannot be written.
void write_file_atomically(const std::string &file, const std::string &text);

/// The outcome of one run under one named configuration (a time-offset mode in `compare`).
struct RunRecord {
  std::string name;
  /// "ok"; otherwise why there is no (full) result: "failed: ...", "skipped: ...", "interrupted", "not run ...".
  std::string status = "ok";
  std::vector<ovton::core::StateSample> traj; ///< estimates, IMU clock, strictly increasing in time
  std::string traj_file;                      ///< where the trajectory was written ("" = nowhere)
  double wall_s = 0.0;                        ///< wall-clock time of the replay
  double data_span_s = 0.0;                   ///< sensor time the replay covered
  long frames = 0;                            ///< images processed
  bool ok() const { return status == "ok"; }
};

/// One row of the table: a run and its evaluation. Metrics that do not apply are NaN (CIT: -1 = never converged).
struct ReportRow {
  std::string name, status;
  bool evaluated = false;
  std::string eval_note; ///< why the run was not evaluated (no ground truth, no overlap, ...)
  EvalResult eval;
  double ape_rmse_m, are_deg, tpe_rmse_mm, final_td_ms, td_sigma_ms, runtime_s, realtime_factor, ms_per_frame;
  double td_err_rmse_ms, td_err_late_ms, td_nees; ///< see EvalResult; NaN without time-offset truth
  int cit = -1;
  bool has_cit = false;
  ReportRow();
};

/// What the report says about where it came from.
struct ReportInfo {
  std::string command_line;       ///< written at the top of results.md so the table can be reproduced
  std::string working_dir;        ///< where the command ran (relative paths in it refer to this); "" = not said
  std::string config;             ///< estimator config file ("" = built-in defaults)
  int jobs = 1;                   ///< runs that shared the machine; timings are per run under that load
  std::vector<std::string> notes; ///< extra lines for results.md (skipped modes, options shared by all runs)
};

struct ReportOptions {
  EvalOptions eval;
  int plot_width = 1200, plot_height = 700;
};

/// The files a report wrote. A plot that could not be drawn (no data for it) is "" and explained in results.md.
struct ReportFiles {
  std::string md, csv, td_png, ape_png, top_png;
};

/// Evaluates each run against the dataset's ground truth and time-offset truth. Never throws for a bad run:
/// a run that cannot be evaluated gets evaluated = false and the reason in eval_note.
std::vector<ReportRow> evaluate_runs(const std::vector<RunRecord> &runs, const ovton::core::Dataset &data,
                                     const ReportOptions &opt = {});

/// results.csv: header `mode,status,ape_rmse_m,are_deg,tpe_rmse_mm,cit_frames,final_td_ms,td_sigma_ms,runtime_s,
/// realtime_factor,ms_per_frame`, one row per run, empty cells where a metric does not apply, CIT -1 when the
/// estimate never converged. Written to a temporary file and renamed, so a reader never sees half a table.
void write_results_csv(const std::string &file, const std::vector<ReportRow> &rows);

/// The table as Markdown (no header lines around it).
std::string results_markdown_table(const std::vector<ReportRow> &rows);

/// results.md: the command line, the dataset, the table, the figures and notes on what the columns mean.
void write_results_md(const std::string &file, const std::vector<ReportRow> &rows, const ovton::core::Dataset &data,
                      const ReportInfo &info, const ReportFiles &files, const ReportOptions &opt = {});

/// t_d estimate of each run [ms] over time, and the truth when the dataset has one. Returns false (and writes
/// nothing) when no run carries a time offset.
bool plot_td(const std::string &file, const std::vector<RunRecord> &runs, const ovton::core::Dataset &data,
             const ReportOptions &opt = {});
/// Aligned position error of each evaluated run over time. Returns false when no run was evaluated.
bool plot_ape(const std::string &file, const std::vector<RunRecord> &runs, const std::vector<ReportRow> &rows,
              const ovton::core::Dataset &data, const ReportOptions &opt = {});
/// x-y top view, equal aspect: ground truth and each run after its alignment (raw when it was not evaluated).
/// Returns false when there is nothing to draw.
bool plot_top(const std::string &file, const std::vector<RunRecord> &runs, const std::vector<ReportRow> &rows,
              const ovton::core::Dataset &data, const ReportOptions &opt = {});

/// Everything above into out_dir (created if needed): results.md, results.csv, td.png, ape.png, top.png.
/// Throws DataError naming a file that cannot be written.
ReportFiles write_report(const std::string &out_dir, const std::vector<RunRecord> &runs,
                         const std::vector<ReportRow> &rows, const ovton::core::Dataset &data, const ReportInfo &info,
                         const ReportOptions &opt = {});

/// Splits a comma-separated list ("off,sr, oracle") and checks every name against `valid`. Throws UsageError naming
/// the first unknown name and listing the valid ones (`what` names the kind of item, e.g. "mode"), or naming a
/// duplicate, or when the list is empty. The order of the list is kept.
std::vector<std::string> parse_name_list(const std::string &list, const std::vector<std::string> &valid,
                                         const std::string &what);

/// Runs `run_one(name)` for every name, at most `jobs` at a time on their own threads, and returns the records in
/// the order of `names`. An exception thrown by one run becomes that record's status ("failed: <what>") and the
/// others go on. `on_done` (may be empty) is called once per finished run, one call at a time, with the number of
/// runs finished so far. When `stop` (may be empty) returns true, runs not yet started are recorded as
/// "not run (interrupted)".
using RunOne = std::function<RunRecord(const std::string &name)>;
using RunDone = std::function<void(const RunRecord &rec, size_t done, size_t total)>;
std::vector<RunRecord> run_parallel(const std::vector<std::string> &names, int jobs, const RunOne &run_one,
                                    const RunDone &on_done = nullptr, const std::function<bool()> &stop = nullptr);

} // namespace ovton::eval
