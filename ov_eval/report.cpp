#include "ov_eval/report.h"
#include "ov_core/io/text_format.h"
#include "ov_core/types/errors.h"
#include "ov_eval/plot.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;

namespace ovton::eval {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string csv_field(const std::string &s) {
  if (s.find_first_of(",\"\n") == std::string::npos)
    return s;
  std::string q = "\"";
  for (char c : s)
    q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

/// A Markdown cell must not contain a bare '|' or a line break.
std::string md_cell(const std::string &s) {
  std::string o;
  for (char c : s) {
    if (c == '|')
      o += "\\|";
    else if (c == '\n')
      o += ' ';
    else
      o += c;
  }
  return o;
}

/// Plots share one time origin (the first image) so that the three figures line up.
int64_t time_origin_ns(const std::vector<RunRecord> &runs, const ovton::core::Dataset &data) {
  if (!data.images.empty())
    return data.images.front().t_cam_ns;
  for (const auto &r : runs)
    if (!r.traj.empty())
      return r.traj.front().t_ns;
  return data.groundtruth.empty() ? 0 : data.groundtruth.front().t_ns;
}

/// The colour of run i is the same in every figure; black is kept for the truth.
cv::Scalar run_color(size_t i) {
  return palette_color(i);
}

const cv::Scalar kTruthColor(0, 0, 0);

/// The reference curve of a plot: black and heavier than the runs' lines.
Series truth_series(const char *name) {
  Series s;
  s.name = name;
  s.color = kTruthColor;
  s.width = 2.5;
  return s;
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%d %H:%M:%S UTC", &tm);
  return buf;
}

} // namespace

void write_file_atomically(const std::string &file, const std::string &text) {
  const std::string tmp = file + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out)
      throw ovton::core::DataError(file, "cannot open for writing");
    out << text;
    out.flush();
    if (!out)
      throw ovton::core::DataError(file, "write failed");
  }
  std::error_code ec;
  fs::rename(tmp, file, ec);
  if (ec)
    throw ovton::core::DataError(file, "cannot move " + tmp + " into place: " + ec.message());
}

ReportRow::ReportRow()
    : ape_rmse_m(kNaN), are_deg(kNaN), tpe_rmse_mm(kNaN), final_td_ms(kNaN), td_sigma_ms(kNaN), runtime_s(kNaN),
      realtime_factor(kNaN), ms_per_frame(kNaN), td_err_rmse_ms(kNaN), td_err_late_ms(kNaN), td_nees(kNaN) {}

std::vector<ReportRow> evaluate_runs(const std::vector<RunRecord> &runs, const ovton::core::Dataset &data,
                                     const ReportOptions &opt) {
  std::vector<ReportRow> rows;
  rows.reserve(runs.size());
  for (const auto &run : runs) {
    ReportRow row;
    row.name = run.name;
    row.status = run.status;
    if (run.wall_s > 0) {
      row.runtime_s = run.wall_s;
      if (run.data_span_s > 0)
        row.realtime_factor = run.data_span_s / run.wall_s;
      if (run.frames > 0)
        row.ms_per_frame = run.wall_s * 1e3 / static_cast<double>(run.frames);
    }
    for (auto it = run.traj.rbegin(); it != run.traj.rend(); ++it)
      if (it->has_td) {
        row.final_td_ms = it->td_s * 1e3;
        row.td_sigma_ms = it->td_sigma_s * 1e3;
        break;
      }
    if (run.traj.empty())
      row.eval_note = "no trajectory";
    else if (!data.has_groundtruth())
      row.eval_note = "the dataset has no ground truth";
    else {
      try {
        row.eval = evaluate(run.traj, data.groundtruth, data.td_truth, opt.eval);
        row.evaluated = true;
        row.ape_rmse_m = row.eval.ape_rmse_m;
        row.are_deg = row.eval.are_rmse_deg;
        if (row.eval.has_tpe) {
          row.tpe_rmse_mm = row.eval.tpe_rmse_mm;
          row.td_err_rmse_ms = row.eval.td_err_rmse_ms;
          row.td_err_late_ms = row.eval.td_err_rmse_late_ms;
          row.td_nees = row.eval.td_nees;
        }
        row.has_cit = row.eval.has_cit;
        row.cit = row.eval.cit;
      } catch (const ovton::core::UsageError &e) {
        // A run too short or off the truth's span is a result to report, not a reason to lose the others.
        row.eval_note = e.what();
      }
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

void write_results_csv(const std::string &file, const std::vector<ReportRow> &rows) {
  std::ostringstream os;
  os << "mode,status,ape_rmse_m,are_deg,tpe_rmse_mm,cit_frames,final_td_ms,td_sigma_ms,runtime_s,realtime_factor,"
        "ms_per_frame,td_err_rmse_ms,td_err_late_ms,td_nees\n";
  for (const auto &r : rows)
    os << csv_field(r.name) << ',' << csv_field(r.status) << ',' << ovton::core::csv_number(r.ape_rmse_m) << ','
       << ovton::core::csv_number(r.are_deg) << ',' << ovton::core::csv_number(r.tpe_rmse_mm) << ','
       << (r.has_cit ? std::to_string(r.cit) : "") << ',' << ovton::core::csv_number(r.final_td_ms) << ','
       << ovton::core::csv_number(r.td_sigma_ms) << ',' << ovton::core::csv_number(r.runtime_s) << ','
       << ovton::core::csv_number(r.realtime_factor) << ',' << ovton::core::csv_number(r.ms_per_frame) << ','
       << ovton::core::csv_number(r.td_err_rmse_ms) << ',' << ovton::core::csv_number(r.td_err_late_ms) << ','
       << ovton::core::csv_number(r.td_nees) << '\n';
  write_file_atomically(file, os.str());
}

std::string results_markdown_table(const std::vector<ReportRow> &rows) {
  std::ostringstream os;
  os << "| mode | status | APE RMSE [m] | ARE [deg] | TPE RMSE [mm] | CIT [frames] | final t_d [ms] | t_d sigma [ms] "
        "| t_d err RMSE [ms] (2nd half) | t_d NEES | runtime [s] | x real time | ms / frame |\n";
  os << "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const auto &r : rows) {
    const std::string cit = !r.has_cit ? "n/a" : r.cit < 0 ? "never" : std::to_string(r.cit);
    os << "| " << md_cell(r.name) << " | " << md_cell(r.status) << " | " << ovton::core::format_fixed(r.ape_rmse_m, 4)
       << " | " << ovton::core::format_fixed(r.are_deg, 3) << " | " << ovton::core::format_fixed(r.tpe_rmse_mm, 3)
       << " | " << cit << " | " << ovton::core::format_fixed(r.final_td_ms, 3) << " | "
       << ovton::core::format_fixed(r.td_sigma_ms, 4) << " | " << ovton::core::format_fixed(r.td_err_rmse_ms, 3) << " ("
       << ovton::core::format_fixed(r.td_err_late_ms, 3) << ") | " << ovton::core::format_fixed(r.td_nees, 2) << " | "
       << ovton::core::format_fixed(r.runtime_s, 2) << " | " << ovton::core::format_fixed(r.realtime_factor, 2) << " | "
       << ovton::core::format_fixed(r.ms_per_frame, 2) << " |\n";
  }
  return os.str();
}

void write_results_md(const std::string &file, const std::vector<ReportRow> &rows, const ovton::core::Dataset &data,
                      const ReportInfo &info, const ReportFiles &files, const ReportOptions &opt) {
  std::ostringstream os;
  os << "# Time-offset modes compared on " << data.root << "\n\n";
  os << "Produced by" << (info.working_dir.empty() ? "" : " (in `" + info.working_dir + "`)") << ":\n\n```\n"
     << info.command_line << "\n```\n\n";
  os << "Written " << utc_now() << ".\n\n";

  os << "## ovton::core::Dataset\n\n";
  os << "- folder: `" << data.root << "` (" << data.kind << "), " << data.images.size() << " images";
  if (data.images.size() > 1)
    os << " over "
       << ovton::core::format_fixed(ovton::core::ns_to_s(data.images.back().t_cam_ns - data.images.front().t_cam_ns), 1)
       << " s";
  os << ", " << data.imu.size() << " IMU readings\n";
  if (data.has_groundtruth())
    os << "- ground truth: " << data.groundtruth.size() << " samples"
       << (data.groundtruth.front().has_orientation ? "" : " (position only: no ARE)") << "\n";
  else
    os << "- ground truth: none (no APE, ARE, TPE)\n";
  if (data.has_td_truth()) {
    double lo = data.td_truth.front().td_s, hi = lo;
    for (const auto &s : data.td_truth)
      lo = std::min(lo, s.td_s), hi = std::max(hi, s.td_s);
    os << "- time-offset truth: " << data.td_truth.size() << " samples, from " << ovton::core::format_fixed(lo * 1e3, 3)
       << " to " << ovton::core::format_fixed(hi * 1e3, 3) << " ms (first "
       << ovton::core::format_fixed(data.td_truth.front().td_s * 1e3, 3) << ", last "
       << ovton::core::format_fixed(data.td_truth.back().td_s * 1e3, 3) << ")\n";
  } else
    os << "- time-offset truth: none (no TPE, no CIT against the truth, no `oracle`)\n";
  if (data.td_prior_s != 0.0)
    os << "- calibration t_d prior: " << ovton::core::format_fixed(data.td_prior_s * 1e3, 3) << " ms\n";
  os << "- estimator config: " << (info.config.empty() ? "built-in defaults" : "`" + info.config + "`") << "\n\n";

  os << "## Results\n\n" << results_markdown_table(rows) << "\n";
  const auto &cit = opt.eval.cit;
  os << "APE and ARE are RMSEs after " << to_string(opt.eval.align)
     << " alignment of the whole estimate to the ground truth. TPE is the RMSE of (t_d estimate - t_d truth) x |v "
        "estimate| (paper eq. 16). CIT is the first frame with |t_d - t_d truth| <= "
     << ovton::core::format_fixed(cit.eps1_s * 1e3, 2)
     << " ms and |t_d(k) - t_d(k-1)| <= " << ovton::core::format_fixed(cit.eps2_s * 1e3, 2)
     << " ms (paper eq. 15), \"never\" if that does not happen. final t_d and its sigma are the filter's values at the "
        "last frame. Runtime is the wall-clock time of the replay with "
     << info.jobs << (info.jobs == 1 ? " run" : " runs")
     << " at a time on this machine (use `--jobs 1` for timings); x real time = data span / runtime.\n\n";

  os << "## Figures\n\n";
  const auto fig = [&](const std::string &png, const char *what) {
    if (png.empty())
      os << "- " << what << ": not drawn (no data for it)\n";
    else
      os << "![" << what << "](" << fs::path(png).filename().string() << ")\n\n";
  };
  fig(files.td_png, data.has_td_truth() ? "t_d estimate and truth over time" : "t_d estimate over time");
  fig(files.ape_png, "aligned position error over time");
  fig(files.top_png, "top view of the aligned trajectories");

  std::vector<std::string> notes = info.notes;
  for (const auto &r : rows)
    if (!r.evaluated && !r.eval_note.empty() && r.status == "ok")
      notes.push_back(r.name + ": not evaluated: " + r.eval_note);
  if (!notes.empty()) {
    os << "\n## Notes\n\n";
    for (const auto &n : notes)
      os << "- " << n << "\n";
  }
  write_file_atomically(file, os.str());
}

namespace {

/// Every comparison plot: the same size from the options, one line per mode.
PlotOptions report_plot(const std::string &title, const char *xlabel, const char *ylabel, const ReportOptions &opt) {
  PlotOptions po;
  po.title = title;
  po.xlabel = xlabel;
  po.ylabel = ylabel;
  po.width = opt.plot_width;
  po.height = opt.plot_height;
  return po;
}

void check_rows(const char *what, const std::vector<RunRecord> &runs, const std::vector<ReportRow> &rows) {
  if (rows.size() != runs.size())
    throw ovton::core::UsageError(std::string(what) + ": " + std::to_string(rows.size()) + " rows for " +
                                  std::to_string(runs.size()) + " runs");
}

} // namespace

bool plot_td(const std::string &file, const std::vector<RunRecord> &runs, const ovton::core::Dataset &data,
             const ReportOptions &opt) {
  const int64_t t0 = time_origin_ns(runs, data);
  Plot plot(report_plot("time offset t_d (t_imu = t_cam + t_d)", "time since the first image [s]", "t_d [ms]", opt));
  bool any = false;
  for (size_t i = 0; i < runs.size(); ++i) {
    Series s;
    s.name = runs[i].name;
    s.color = run_color(i);
    for (const auto &e : runs[i].traj)
      if (e.has_td) {
        s.x.push_back(ovton::core::ns_to_s(e.t_ns - t0));
        s.y.push_back(e.td_s * 1e3);
      }
    if (s.x.empty())
      continue;
    any = true;
    plot.add(std::move(s));
  }
  if (!any)
    return false;
  if (data.has_td_truth()) {
    // Truth is keyed by camera stamp; drawn at the IMU-clock instant it refers to, like the estimates.
    Series s = truth_series("truth");
    for (const auto &t : data.td_truth) {
      s.x.push_back(ovton::core::ns_to_s(t.t_cam_ns - t0) + t.td_s);
      s.y.push_back(t.td_s * 1e3);
    }
    plot.add(std::move(s));
  }
  plot.save_png(file);
  return true;
}

bool plot_ape(const std::string &file, const std::vector<RunRecord> &runs, const std::vector<ReportRow> &rows,
              const ovton::core::Dataset &data, const ReportOptions &opt) {
  check_rows("plot_ape", runs, rows);
  const int64_t t0 = time_origin_ns(runs, data);
  Plot plot(report_plot(std::string("position error after ") + to_string(opt.eval.align) + " alignment",
                        "time since the first image [s]", "APE [m]", opt));
  bool any = false;
  for (size_t i = 0; i < runs.size(); ++i) {
    if (!rows[i].evaluated)
      continue;
    // The same association evaluate() used, for the stamps of ape_per_pose_m.
    const Association a = associate(runs[i].traj, data.groundtruth, opt.eval.max_gap_s);
    const auto &err = rows[i].eval.ape_per_pose_m;
    if (a.est.size() != err.size())
      continue;
    Series s;
    s.name = runs[i].name;
    s.color = run_color(i);
    for (size_t k = 0; k < err.size(); ++k) {
      s.x.push_back(ovton::core::ns_to_s(a.est[k].t_ns - t0));
      s.y.push_back(err[k]);
    }
    any = true;
    plot.add(std::move(s));
  }
  if (!any)
    return false;
  plot.save_png(file);
  return true;
}

bool plot_top(const std::string &file, const std::vector<RunRecord> &runs, const std::vector<ReportRow> &rows,
              const ovton::core::Dataset &data, const ReportOptions &opt) {
  check_rows("plot_top", runs, rows);
  PlotOptions po = report_plot(std::string("top view (estimates after ") + to_string(opt.eval.align) + " alignment)",
                               "x [m]", "y [m]", opt);
  po.width = std::max(opt.plot_height, 400) + 200; // near-square: a top view's spans are alike
  po.height = std::max(opt.plot_height, 400);
  po.equal_aspect = true;
  Plot plot(po);
  bool any = false;
  if (data.has_groundtruth()) {
    Series s = truth_series("ground truth");
    for (const auto &g : data.groundtruth) {
      s.x.push_back(g.p.x());
      s.y.push_back(g.p.y());
    }
    plot.add(std::move(s));
    any = true;
  }
  for (size_t i = 0; i < runs.size(); ++i) {
    if (runs[i].traj.empty())
      continue;
    Series s;
    s.name = rows[i].evaluated ? runs[i].name : runs[i].name + " (not aligned)";
    s.color = run_color(i);
    const Alignment al = rows[i].evaluated ? rows[i].eval.alignment : Alignment{};
    for (const auto &e : runs[i].traj) {
      const Eigen::Vector3d p = al.apply(e.p);
      s.x.push_back(p.x());
      s.y.push_back(p.y());
    }
    plot.add(std::move(s));
    any = true;
  }
  if (!any)
    return false;
  plot.save_png(file);
  return true;
}

ReportFiles write_report(const std::string &out_dir, const std::vector<RunRecord> &runs,
                         const std::vector<ReportRow> &rows, const ovton::core::Dataset &data, const ReportInfo &info,
                         const ReportOptions &opt) {
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec)
    throw ovton::core::DataError(out_dir, "cannot create the output folder: " + ec.message());
  const fs::path dir(out_dir);
  ReportFiles f;
  f.csv = (dir / "results.csv").string();
  write_results_csv(f.csv, rows);
  const std::string td = (dir / "td.png").string(), ape = (dir / "ape.png").string(), top = (dir / "top.png").string();
  if (plot_td(td, runs, data, opt))
    f.td_png = td;
  if (plot_ape(ape, runs, rows, data, opt))
    f.ape_png = ape;
  if (plot_top(top, runs, rows, data, opt))
    f.top_png = top;
  f.md = (dir / "results.md").string();
  write_results_md(f.md, rows, data, info, f, opt);
  return f;
}

std::vector<std::string> parse_name_list(const std::string &list, const std::vector<std::string> &valid,
                                         const std::string &what) {
  std::vector<std::string> out;
  std::string valid_text;
  for (const auto &v : valid)
    valid_text += (valid_text.empty() ? "" : ", ") + v;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const size_t b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    const std::string name = b == std::string::npos ? "" : item.substr(b, e - b + 1);
    if (name.empty())
      throw ovton::core::UsageError("empty " + what + " name in the list '" + list + "'");
    if (std::find(valid.begin(), valid.end(), name) == valid.end())
      throw ovton::core::UsageError("unknown " + what + " '" + name + "' (expected one of: " + valid_text + ")");
    if (std::find(out.begin(), out.end(), name) != out.end())
      throw ovton::core::UsageError(what + " '" + name + "' is listed twice in '" + list + "'");
    out.push_back(name);
  }
  if (out.empty())
    throw ovton::core::UsageError("no " + what + " given (expected a comma-separated list of: " + valid_text + ")");
  return out;
}

std::vector<RunRecord> run_parallel(const std::vector<std::string> &names, int jobs, const RunOne &run_one,
                                    const RunDone &on_done, const std::function<bool()> &stop) {
  const size_t n = names.size();
  std::vector<RunRecord> records(n);
  std::atomic<size_t> next{0};
  std::mutex done_mutex;
  size_t done = 0;
  std::exception_ptr callback_error;

  const auto worker = [&]() {
    for (size_t i = next++; i < n; i = next++) {
      RunRecord rec;
      if (stop && stop()) {
        rec.status = "not run (interrupted)";
      } else {
        try {
          rec = run_one(names[i]);
        } catch (const std::exception &e) {
          rec = RunRecord{};
          rec.status = std::string("failed: ") + e.what();
        } catch (...) {
          rec = RunRecord{};
          rec.status = "failed: unknown error";
        }
      }
      rec.name = names[i];
      records[i] = std::move(rec);
      std::lock_guard<std::mutex> lock(done_mutex);
      ++done;
      // An exception must not leave a worker thread (std::terminate); the first one is rethrown after the join.
      if (on_done && !callback_error) {
        try {
          on_done(records[i], done, n);
        } catch (...) {
          callback_error = std::current_exception();
        }
      }
    }
  };

  const size_t n_threads = std::min(n, static_cast<size_t>(std::max(1, jobs)));
  if (n_threads <= 1) {
    worker(); // no thread for a single job: simpler stacks in a debugger, same behaviour
  } else {
    std::vector<std::thread> pool;
    try {
      for (size_t t = 0; t < n_threads; ++t)
        pool.emplace_back(worker);
    } catch (...) {
      // The threads already started take every remaining run; they must be joined before the error leaves.
      for (auto &t : pool)
        t.join();
      throw;
    }
    for (auto &t : pool)
      t.join();
  }
  if (callback_error)
    std::rethrow_exception(callback_error);
  return records;
}

} // namespace ovton::eval
