// `ovton diagnose`'s report: the ranking table the CLI prints, diagnose.md, diagnose.json and the plots.
#include "ov_core/io/csv.h"
#include "ov_core/io/text_format.h"
#include "ov_core/types/errors.h"
#include "ov_eval/diagnose.h"
#include "ov_eval/plot.h"
#include "ov_eval/report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

namespace ovton::eval {

namespace {

std::string estimates_text(const CandidateResult &c) {
  std::string s;
  for (const auto &e : c.estimates) {
    if (!s.empty())
      s += "; ";
    s += e.name + " " + ovton::core::format_fixed(e.value, 3) + " ± " + ovton::core::format_fixed(e.stderr_, 3) +
         (e.unit.empty() ? "" : " " + e.unit);
  }
  return s.empty() ? "-" : s;
}

/// The plots' font is ASCII: the few Greek letters and symbols of the model texts spelled out.
std::string ascii_text(const std::string &in) {
  static const std::vector<std::pair<std::string, std::string>> map = {
      {"·", "*"},     {"δ", "d"},    {"ω", "w"},  {"α", "alpha "}, {"ε", "eps"}, {"ḋ", "rate"}, {"−", "-"}, {"±", "+-"},
      {"Θ", "Theta"}, {"∫", "int "}, {"²", "^2"}, {"‖", "|"},      {"—", "-"},   {"√", "sqrt"}, {"t̂", "t^"}};
  std::string s = in;
  for (const auto &[from, to] : map)
    for (size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size()))
      s.replace(p, from.size(), to);
  std::string out;
  for (unsigned char ch : s)
    if (ch < 0x80)
      out += static_cast<char>(ch);
  return out;
}

/// Bin means with ±1 SE bars (vertical segments broken by NaN) and the fitted line.
void plot_curve(const CandidateResult &c, const std::string &file) {
  const BinnedCurve &cu = c.curve;
  PlotOptions po;
  po.title =
      ascii_text("#" + std::to_string(c.rank) + " " + c.key + ": " + c.description.substr(0, c.description.find(':')));
  po.xlabel = cu.xlabel;
  po.ylabel = cu.ylabel;
  Plot p(po);
  std::vector<double> ex, ey;
  for (size_t i = 0; i < cu.x.size(); ++i) {
    ex.insert(ex.end(), {cu.x[i], cu.x[i], std::nan("")});
    ey.insert(ey.end(), {cu.mean[i] - cu.se[i], cu.mean[i] + cu.se[i], std::nan("")});
  }
  Series bars("", ex, ey, Series::Style::Line);
  bars.color = cv::Scalar(60, 60, 60);
  p.add(bars);
  Series pts("bin mean (+-1 SE)", cu.x, cu.mean, Series::Style::Points);
  pts.width = 4;
  p.add(pts);
  p.add_line(cu.slope, cu.intercept, ascii_text("fit: " + estimates_text(c)).substr(0, 70));
  p.save_png(file);
}

void plot_td_bins(const DiagnoseReport &rep, const std::string &file) {
  PlotOptions po;
  po.title = rep.time_from_rates ? "time-offset error per time bin (true - filter's t_d), w_vis - w_gyro = alpha*dt"
                                 : "time-offset error per time bin (true - filter's t_d), from r = V*dt in each bin";
  po.xlabel = "time since first logged row [s]";
  po.ylabel = "offset [ms]";
  Plot p(po);
  std::vector<double> x, y, yt, ex, ey;
  for (const auto &b : rep.td_bins) {
    x.push_back(b.t_s), y.push_back(b.td_ms), yt.push_back(b.td_filter_ms + b.td_ms);
    ex.insert(ex.end(), {b.t_s, b.t_s, std::nan("")});
    ey.insert(ey.end(), {b.td_ms - b.td_se_ms, b.td_ms + b.td_se_ms, std::nan("")});
  }
  Series bars("", ex, ey, Series::Style::Line);
  bars.color = cv::Scalar(60, 60, 60);
  p.add(bars);
  Series pts("offset error dt (+-1 SE)", x, y, Series::Style::Points);
  pts.width = 4;
  p.add(pts);
  p.add(Series("filter t_d + dt (implied true offset)", x, yt, Series::Style::Line));
  for (const auto &c : rep.candidates)
    if (c.key == "td_drift" && c.estimates.size() >= 3)
      p.add_line(c.estimates[0].value, c.estimates[2].value - c.estimates[0].value * 0.5 * rep.duration_s,
                 "td_drift fit: " + ovton::core::format_fixed(c.estimates[0].value, 3) + " ms/s");
  p.add_hline(0.0);
  p.save_png(file);
}

/// A candidate's verdict as shown: `explained` (the selection's), not testable on this log, or not explained.
std::string verdict(const CandidateResult &c, const char *explained) {
  return c.explained ? explained : c.testable ? "not explained" : "not testable";
}

/// The first candidate the selection explains the residual with; null when none.
const CandidateResult *top_effect(const DiagnoseReport &rep) {
  const auto it = std::find_if(rep.candidates.begin(), rep.candidates.end(), [](auto &c) { return c.explained; });
  return it == rep.candidates.end() ? nullptr : &*it;
}

/// (key, file name) of each plot written.
using PlotList = std::vector<std::pair<std::string, std::string>>;

/// The top three candidates' curves and, with two bins or more, the offset per time bin.
PlotList write_plots(const DiagnoseReport &rep, const std::string &out_dir) {
  PlotList plots;
  int plotted = 0;
  for (const auto &c : rep.candidates) {
    if (plotted >= 3)
      break;
    if (c.curve.x.size() < 2)
      continue;
    const std::string name = "diagnose_" + std::to_string(c.rank) + "_" + c.key + ".png";
    plot_curve(c, ovton::core::join_path(out_dir, name));
    plots.push_back({c.key, name});
    ++plotted;
  }
  if (rep.td_bins.size() >= 2) {
    const std::string name = "diagnose_td_per_time_bin.png";
    plot_td_bins(rep, ovton::core::join_path(out_dir, name));
    plots.push_back({"td_bins", name});
  }
  return plots;
}

std::string markdown_text(const DiagnoseReport &rep, const PlotList &plots) {
  const auto &o = rep.options;
  std::ostringstream md;
  md << "# Residual diagnosis\n\n"
     << "Log: `" << rep.log_file << "`\n\n"
     << "- rows read " << rep.rows_read << "; used " << rep.rows_used << " observations in " << rep.tracks_used
     << " tracks (accepted + chi-square gated); " << rep.rows_triangulation_failed << " triangulation-failure rows and "
     << rep.rows_without_velocity << " rows without image velocity left out\n"
     << "- span " << ovton::core::format_fixed(rep.duration_s, 1) << " s; residual RMS "
     << ovton::core::format_fixed(rep.residual_rms_px, 3) << " px, robust sigma "
     << ovton::core::format_fixed(rep.robust_sigma_px, 3) << " px\n"
     << "- intrinsics " << (rep.intrinsics_fitted ? "fitted from the log" : "from the dataset") << ": fu "
     << ovton::core::format_fixed(rep.fu, 1) << ", fv " << ovton::core::format_fixed(rep.fv, 1) << ", cu "
     << ovton::core::format_fixed(rep.cu, 1) << ", cv " << ovton::core::format_fixed(rep.cv, 1) << " px; image height "
     << rep.image_height << " px; image velocity "
     << (o.use_logged_velocity ? "from the log's column" : "from the track's predicted positions") << "\n"
     << "- time candidates: "
     << (rep.time_from_rates ? "the images' angular rate against the raw gyro's at the filter's image time"
                             : "on the residual (no raw gyro: pass --dataset); a lower bound")
     << "\n"
     << "- verdict rule: EXPLAINED when selected by forward stepwise regression: significance >= "
     << ovton::core::format_fixed(o.min_sigma, 1)
     << " sigma (Wald against F with the data's independent clusters: the residual's per quarter second of its "
        "updates, Newey-West over the clone window) and >= "
     << ovton::core::format_fixed(100 * o.min_explained, 1)
     << " % of the Huber loss of its data (the residual; for time candidates from rates, the rate mismatch) removed "
        "beyond the candidates selected before it\n\n";
  const CandidateResult *first = top_effect(rep);
  if (!rep.not_testable.empty())
    md << "**Nothing is testable on this log**: " << rep.not_testable << ".\n\n";
  else if (!first)
    md << "**No candidate explains the residuals** (nothing passes both thresholds).\n\n";
  else
    md << "**Top effect: " << first->key << "** — " << first->description << "; " << estimates_text(*first)
       << "; removes " << ovton::core::format_fixed(100 * first->explained_added, 1) << " % of the "
       << (rep.time_from_rates && first->key.rfind("td_", 0) == 0 ? "rate mismatch's" : "residual's") << " loss.\n\n";
  md << "| rank | candidate | verdict | explained alone [%] | added [%] | sigma | estimate (± 1 SE) | note |\n"
     << "|---:|---|---|---:|---:|---:|---|---|\n";
  for (const auto &c : rep.candidates)
    md << "| " << c.rank << " | " << c.key << " | " << verdict(c, "**explained**") << " | "
       << ovton::core::format_fixed(100 * c.explained_alone, 2) << " | "
       << ovton::core::format_fixed(100 * c.explained_added, 2) << " | " << ovton::core::format_fixed(c.sigma, 1)
       << " | " << estimates_text(c) << " | " << c.note << " |\n";
  md << "\nModels:\n\n";
  for (const auto &c : rep.candidates)
    md << "- `" << c.key << "`: " << c.description << "\n";
  if (!rep.td_bins.empty()) {
    md << "\nTime-offset error per time bin (each bin fitted alone, r = V·δt):\n\n"
       << "| t [s] | δt [ms] | SE [ms] | filter t̂_d [ms] | t̂_d + δt [ms] | observations |\n"
       << "|---:|---:|---:|---:|---:|---:|\n";
    for (const auto &b : rep.td_bins)
      md << "| " << ovton::core::format_fixed(b.t_s, 1) << " | " << ovton::core::format_fixed(b.td_ms, 3) << " | "
         << ovton::core::format_fixed(b.td_se_ms, 3) << " | " << ovton::core::format_fixed(b.td_filter_ms, 3) << " | "
         << ovton::core::format_fixed(b.td_filter_ms + b.td_ms, 3) << " | " << b.observations << " |\n";
  }
  if (!plots.empty()) {
    md << "\nPlots:\n\n";
    for (const auto &pl : plots)
      md << "![" << pl.first << "](" << pl.second << ")\n";
  }
  md << "\nCaveat: residuals are logged after the filter has absorbed part of any effect into its state (poses, "
        "biases, t̂_d); what the tracks' points absorb is projected out, what the poses absorb is not. Residual-based "
        "sizes are therefore lower bounds (docs/diagnose.md, \"What the residuals cannot show\").\n";
  return md.str();
}

std::string json_text(const DiagnoseReport &rep) {
  const auto &o = rep.options;
  const CandidateResult *first = top_effect(rep);
  std::ostringstream js;
  js << "{\n  \"log\": " << ovton::core::json_string(rep.log_file) << ",\n  \"rows_read\": " << rep.rows_read
     << ",\n  \"rows_used\": " << rep.rows_used << ",\n  \"tracks_used\": " << rep.tracks_used
     << ",\n  \"rows_triangulation_failed\": " << rep.rows_triangulation_failed
     << ",\n  \"rows_without_velocity\": " << rep.rows_without_velocity
     << ",\n  \"duration_s\": " << ovton::core::json_number(rep.duration_s)
     << ",\n  \"residual_rms_px\": " << ovton::core::json_number(rep.residual_rms_px)
     << ",\n  \"robust_sigma_px\": " << ovton::core::json_number(rep.robust_sigma_px)
     << ",\n  \"intrinsics\": {\"fu\": " << ovton::core::json_number(rep.fu)
     << ", \"fv\": " << ovton::core::json_number(rep.fv) << ", \"cu\": " << ovton::core::json_number(rep.cu)
     << ", \"cv\": " << ovton::core::json_number(rep.cv)
     << ", \"fitted\": " << (rep.intrinsics_fitted ? "true" : "false") << "},\n  \"image_height\": " << rep.image_height
     << ",\n  \"min_sigma\": " << ovton::core::json_number(o.min_sigma)
     << ",\n  \"min_explained\": " << ovton::core::json_number(o.min_explained)
     << ",\n  \"not_testable\": " << (rep.not_testable.empty() ? "null" : ovton::core::json_string(rep.not_testable))
     << ",\n  \"top\": " << (first ? ovton::core::json_string(first->key) : "null") << ",\n  \"candidates\": [";
  for (size_t c = 0; c < rep.candidates.size(); ++c) {
    const auto &cr = rep.candidates[c];
    js << (c ? "," : "") << "\n    {\"rank\": " << cr.rank << ", \"key\": " << ovton::core::json_string(cr.key)
       << ", \"model\": " << ovton::core::json_string(cr.description)
       << ", \"explained\": " << (cr.explained ? "true" : "false")
       << ", \"testable\": " << (cr.testable ? "true" : "false")
       << ", \"explained_alone\": " << ovton::core::json_number(cr.explained_alone)
       << ", \"explained_added\": " << ovton::core::json_number(cr.explained_added)
       << ", \"sigma\": " << ovton::core::json_number(cr.sigma) << ", \"note\": " << ovton::core::json_string(cr.note)
       << ", \"estimates\": [";
    for (size_t e = 0; e < cr.estimates.size(); ++e)
      js << (e ? ", " : "") << "{\"name\": " << ovton::core::json_string(cr.estimates[e].name)
         << ", \"unit\": " << ovton::core::json_string(cr.estimates[e].unit)
         << ", \"value\": " << ovton::core::json_number(cr.estimates[e].value)
         << ", \"stderr\": " << ovton::core::json_number(cr.estimates[e].stderr_) << "}";
    js << "]}";
  }
  js << "\n  ],\n  \"td_bins\": [";
  for (size_t b = 0; b < rep.td_bins.size(); ++b) {
    const auto &tb = rep.td_bins[b];
    js << (b ? "," : "") << "\n    {\"t_s\": " << ovton::core::json_number(tb.t_s)
       << ", \"td_error_ms\": " << ovton::core::json_number(tb.td_ms)
       << ", \"td_error_se_ms\": " << ovton::core::json_number(tb.td_se_ms)
       << ", \"td_filter_ms\": " << ovton::core::json_number(tb.td_filter_ms)
       << ", \"observations\": " << tb.observations << "}";
  }
  js << "\n  ],\n  \"unexplained\": [";
  for (size_t u = 0; u < rep.unexplained.size(); ++u) {
    const auto &ue = rep.unexplained[u];
    js << (u ? "," : "") << "\n    {\"where\": " << ovton::core::json_string(ue.where)
       << ", \"flagged\": " << (ue.flagged ? "true" : "false") << ", \"testable\": " << (ue.testable ? "true" : "false")
       << ", \"explained\": " << ovton::core::json_number(ue.explained)
       << ", \"sigma\": " << ovton::core::json_number(ue.sigma)
       << ", \"largest\": " << ovton::core::json_string(ue.largest) << "}";
  }
  js << "\n  ]\n}\n";
  return js.str();
}

} // namespace

std::string format_ranking(const DiagnoseReport &rep) {
  std::ostringstream os;
  if (!rep.not_testable.empty())
    os << "nothing testable on this log: " << rep.not_testable << "\n\n";
  os << "rank  candidate              verdict        alone[%]  added[%]   sigma  estimate\n";
  for (const auto &c : rep.candidates) {
    os << std::left << std::setw(6) << c.rank << std::setw(23) << c.key << std::setw(15) << verdict(c, "EXPLAINED")
       << std::right << std::setw(8) << ovton::core::format_fixed(100 * c.explained_alone, 2) << std::setw(10)
       << ovton::core::format_fixed(100 * c.explained_added, 2) << std::setw(8) << ovton::core::format_fixed(c.sigma, 1)
       << "  " << estimates_text(c) << (c.note.empty() ? "" : "  [" + c.note + "]") << "\n";
  }
  // Structure no candidate explains: the verdict UNEXPLAINED, with its size and where it shows.
  for (const auto &u : rep.unexplained)
    os << "      " << std::left << std::setw(23) << ("by " + u.where) << std::setw(15)
       << (u.flagged    ? "UNEXPLAINED"
           : u.testable ? "noise"
                        : "not testable")
       << std::right << std::setw(8) << ovton::core::format_fixed(100 * u.explained, 2) << std::setw(10) << ""
       << std::setw(8) << ovton::core::format_fixed(u.sigma, 1) << "  leftover's bin means; largest " << u.largest
       << "\n";
  return os.str();
}

std::vector<std::string> write_diagnose_report(const DiagnoseReport &rep, const std::string &out_dir) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (!std::filesystem::is_directory(out_dir))
    throw ovton::core::DataError(out_dir, "cannot create the output folder");
  // Plots first, so the report can link them.
  const PlotList plots = write_plots(rep, out_dir);
  const std::string md_file = ovton::core::join_path(out_dir, "diagnose.md");
  const std::string js_file = ovton::core::join_path(out_dir, "diagnose.json");
  write_file_atomically(md_file, markdown_text(rep, plots));
  write_file_atomically(js_file, json_text(rep));
  std::vector<std::string> files = {md_file, js_file};
  for (const auto &pl : plots)
    files.push_back(ovton::core::join_path(out_dir, pl.second));
  return files;
}

} // namespace ovton::eval
