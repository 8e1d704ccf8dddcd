#include "tools/compare_report.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/td/td_model_check.h"
#include "tools/progress.h"
#include "tools/run_pipeline.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <ostream>
#include <sstream>

namespace fs = std::filesystem;

namespace ovton::cli {

namespace {

/// One line for the log: the numbers a user watching a long comparison wants before the table is written.
std::string done_line(const ovton::eval::RunRecord &rec, const ovton::eval::ReportRow &row, size_t done, size_t total) {
  char buf[512];
  int n =
      std::snprintf(buf, sizeof(buf), "compare [%zu/%zu] %s: %s", done, total, rec.name.c_str(), rec.status.c_str());
  const auto add = [&](const char *fmt, double v) {
    if (std::isfinite(v) && n >= 0 && n < static_cast<int>(sizeof(buf)))
      n += std::snprintf(buf + n, sizeof(buf) - n, fmt, v);
  };
  if (!rec.traj.empty()) {
    add(", %.0f poses", static_cast<double>(rec.traj.size()));
    add(", APE %.4f m", row.ape_rmse_m);
    add(", TPE %.3f mm", row.tpe_rmse_mm);
    add(", final t_d %.3f ms", row.final_td_ms);
  }
  add(", %.1f s", row.runtime_s);
  add(" (%.1fx real time)", row.realtime_factor);
  return buf;
}

} // namespace

std::vector<ovton::msckf::ModeSpec> parse_compare_modes(const std::string &list) {
  // Every MODE+PROCESS combination is valid; the name list checks emptiness and repeats, the spec parser the rest.
  std::vector<std::string> valid;
  std::stringstream ss(list);
  for (std::string item; std::getline(ss, item, ',');) {
    const size_t b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    if (b != std::string::npos)
      valid.push_back(ovton::msckf::parse_mode_spec(item.substr(b, e - b + 1)).name);
  }
  std::vector<ovton::msckf::ModeSpec> modes;
  for (const auto &name :
       ovton::eval::parse_name_list(list, valid.empty() ? ovton::msckf::all_td_mode_names() : valid, "mode"))
    modes.push_back(ovton::msckf::parse_mode_spec(name));
  return modes;
}

CompareResult run_compare(const ovton::core::Dataset &data, const CompareRequest &req) {
  using ovton::msckf::TdMode;
  if (req.modes.empty())
    throw ovton::core::UsageError("compare: no mode to run");
  // Every run would fail the same way: say it once, before spending any time.
  if (req.base.init.mode == ovton::msckf::InitMode::GroundTruth &&
      (!data.has_groundtruth() || !data.groundtruth.front().has_velocity))
    throw ovton::core::UsageError("ground-truth initialisation needs full-state ground truth in " + data.root +
                                  " (use --init static)");
  std::error_code ec;
  fs::create_directories(req.out_dir, ec);
  if (ec)
    throw ovton::core::DataError(req.out_dir, "cannot create the output folder: " + ec.message());

  ovton::eval::ReportInfo info = req.info;

  std::vector<std::string> to_run;
  std::map<std::string, ovton::eval::RunRecord> skipped;
  std::map<std::string, ovton::msckf::ModeSpec> spec_of;
  for (const auto &spec : req.modes) {
    const std::string &name = spec.name;
    spec_of[name] = spec;
    if (spec.mode == TdMode::Oracle && !data.has_td_truth()) {
      ovton::eval::RunRecord rec;
      rec.name = name;
      rec.status = "skipped: no td_truth/data.csv";
      info.notes.push_back("oracle skipped: " + data.root +
                           " has no time-offset truth (td_truth/data.csv), which the oracle mode reads");
      if (req.log)
        *req.log << "compare: " << info.notes.back() << "\n" << std::flush;
      skipped[name] = std::move(rec);
      continue;
    }
    to_run.push_back(name);
  }

  info.jobs = std::max(1, std::min(req.jobs, static_cast<int>(to_run.size())));

  // Every mode that estimates t_d runs the same coarse search on the same images (the others keep their offset): the
  // report quotes the first one's outcome.
  std::mutex search_mutex;
  std::optional<ovton::msckf::TdSearchResult> search;
  std::map<std::string, std::string> switched; // per mode, the t_d model check's line (guarded by search_mutex)
  const auto run_one = [&](const std::string &name) {
    RunRequest rr;
    const ovton::msckf::ModeSpec &spec = spec_of.at(name);
    rr.opt = req.base;
    ovton::msckf::apply_mode_spec(spec, rr.opt);
    rr.output = (fs::path(req.out_dir) / ("traj_" + name + ".csv")).string();
    rr.max_images = req.max_images;
    rr.progress = false;
    rr.threaded = false; // the modes run side by side, one thread each // parallel bars would overwrite each other; the
                         // log has one line per finished mode
    // A diverged filter (EstimatorFailure) or a run without a single pose (DataError) throws: run_parallel makes
    // that the mode's status, "failed: <why>".
    RunResult r = run_dataset(data, rr);
    {
      const std::lock_guard<std::mutex> lock(search_mutex);
      if (r.report.td_search && !search)
        search = r.report.td_search;
      if (!r.traj.empty())
        if (std::string sw = ovton::msckf::describe_model_check(r.report.td_model, r.traj.front().t_ns, rr.opt.td);
            !sw.empty())
          switched[name] = std::move(sw);
    }
    ovton::eval::RunRecord rec;
    rec.name = name;
    rec.traj = std::move(r.traj);
    rec.traj_file = rr.output;
    rec.wall_s = r.play.wall_s;
    rec.data_span_s = r.play.data_span_s;
    rec.frames = static_cast<long>(r.play.images_fed);
    if (r.play.interrupted)
      rec.status = "interrupted";
    return rec;
  };
  const auto on_done = [&](const ovton::eval::RunRecord &rec, size_t done, size_t total) {
    if (!req.log)
      return;
    const auto rows = ovton::eval::evaluate_runs({rec}, data, req.report);
    *req.log << done_line(rec, rows.front(), done, total) << "\n" << std::flush;
  };
  std::vector<ovton::eval::RunRecord> ran = ovton::eval::run_parallel(to_run, req.jobs, run_one, on_done, interrupted);

  CompareResult res;
  size_t k = 0;
  for (const auto &spec : req.modes) {
    auto it = skipped.find(spec.name);
    res.runs.push_back(it != skipped.end() ? std::move(it->second) : std::move(ran[k++]));
  }
  for (const auto &r : res.runs) {
    res.failed += r.status.rfind("failed", 0) == 0;
    res.interrupted = res.interrupted || r.status == "interrupted" || r.status.rfind("not run", 0) == 0;
  }
  if (search) {
    info.notes.push_back("coarse t_d search (the same in every mode that estimates t_d): " + search->summary());
    if (req.log)
      *req.log << "compare: " << info.notes.back() << "\n" << std::flush;
    if (search->weak_excitation) {
      info.notes.push_back(search->caution());
      if (req.log)
        *req.log << "compare: " << info.notes.back() << "\n" << std::flush;
    }
  }
  // A mode whose t_d model went to the drift state ran another model from there: its row says what it ended as.
  for (const auto &spec : req.modes)
    if (auto it = switched.find(spec.name); it != switched.end()) {
      info.notes.push_back(spec.name + ": " + it->second);
      if (req.log)
        *req.log << "compare: " << info.notes.back() << "\n" << std::flush;
    }
  res.rows = ovton::eval::evaluate_runs(res.runs, data, req.report);
  res.files = ovton::eval::write_report(req.out_dir, res.runs, res.rows, data, info, req.report);
  return res;
}

} // namespace ovton::cli
