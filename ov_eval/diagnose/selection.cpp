#include "ov_eval/diagnose/selection.h"
#include "ov_eval/diagnose/candidates.h"
#include "ov_eval/diagnose/rate_design.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ovton::eval::diag {

namespace {

/// A candidate the log cannot resolve at the size a calibration is plausibly off by (CandidateDef::testable_size):
/// the smallest size it could name — its first estimate's SE times the bar's Wald statistic, against F with the
/// design's independent clusters — is larger. Reported as not testable, not as "no effect".
void mark_weak(const CandidateDef &def, int terms, double df, double min_sigma, CandidateResult &cr) {
  const EffectEstimate &e = cr.estimates.front();
  const double smallest = std::sqrt(wald_at_sigma(min_sigma, terms, df)) * e.stderr_;
  if (!(smallest > def.testable_size))
    return;
  cr.testable = false;
  char buf[200];
  const std::string unit = e.unit.empty() ? "" : " " + e.unit;
  std::snprintf(buf, sizeof(buf),
                "not testable on this log: the smallest %s it could name is %.3g%s (%.3g%s: 3 prior "
                "sigma of the filter's calibration)",
                e.name.c_str(), smallest, unit.c_str(), def.testable_size, unit.c_str());
  cr.note = buf + (cr.note.empty() ? std::string() : "; " + cr.note);
}

/// Runs the stepwise selection on one family (indices into the table) and writes its verdicts into res.
std::vector<size_t> test_family(const Design &d, const std::vector<size_t> &family, bool on_rates, bool on_bias,
                                const std::string &bias_why, const DiagnoseOptions &opt, const DiagnoseReport &rep,
                                std::vector<CandidateResult> &res) {
  const auto &table = candidate_table();
  std::vector<StepCandidate> cands;
  for (size_t c : family) {
    const CandidateDef &def = table[c];
    StepCandidate sc{def.key, def.columns(opt.have_camera), ""};
    if (def.needs == Needs::Velocity && !d.have_velocity)
      sc.skip = "skipped: fewer than " + std::to_string(int(100 * opt.min_velocity_share)) +
                "% of rows carry an image velocity";
    if (def.needs == Needs::AccelBias && !on_bias)
      sc.skip = "skipped: tested on the accelerometer only (" + bias_why + ")";
    if (!on_rates && def.needs == Needs::Rates)
      sc.skip = "skipped: tested on rates only (needs --dataset: the raw gyro and the camera)";
    if (!on_rates && def.needs == Needs::BodyRates && !d.have_rate)
      sc.skip = "skipped: most tracks lack body rates (w_valid)";
    cands.push_back(sc);
  }
  std::vector<StepResult> steps;
  const std::vector<size_t> sel = stepwise(d, cands, {opt.min_sigma, opt.min_explained, opt.huber_k}, steps);
  for (size_t i = 0; i < family.size(); ++i) {
    const CandidateDef &def = table[family[i]];
    const StepResult &s = steps[i];
    CandidateResult &cr = res[family[i]];
    cr.explained_alone = s.explained_alone;
    cr.explained_added = s.explained_added;
    cr.sigma = s.sigma;
    cr.explained = s.selected;
    if (!s.note.empty())
      cr.note = s.note;
    if (!s.joint.empty())
      cr.estimates = candidate_estimates(def, cands[i].cols, s.fit, s.joint, rep, d);
    cr.testable = s.testable;
    if (!s.selected && s.testable && s.terms > 0 && def.testable_size > 0 && !cr.estimates.empty())
      mark_weak(def, s.terms, d.wald_df(), opt.min_sigma, cr);
    if (!s.joint.empty() && !s.nested) {
      cr.curve = binned_curve(cands[i].cols, d, s.fit, s.joint, opt.plot_bins);
      cr.curve.xlabel = def.xlabel;
      cr.curve.ylabel = "residual, other selected effects removed [px] (bin mean +- SE)";
    }
    if (on_bias && d.accel_against_gravity) {
      cr.curve.xlabel = "fitted accel_scale_axes effect [m/s]";
      cr.curve.ylabel = "IMU's velocity change less the filter's, bias and trajectory scale removed [m/s] (bin mean "
                        "+- SE)";
    } else if (on_bias) {
      cr.curve.ylabel = "filter's accel bias, bin means removed [m/s^2] (bin mean +- SE)";
    }
    if (on_rates) {
      cr.curve.xlabel = def.rate_xlabel;
      cr.curve.ylabel = "w_vis - w_gyro (bias removed) and psi_vis, / SE (bin mean +- SE)";
    }
  }
  std::vector<size_t> out;
  for (size_t i : sel)
    out.push_back(family[i]);
  return out;
}

} // namespace

std::vector<CandidateResult> test_candidates(const Design &d, const Design *rates, const std::string &rate_why,
                                             const Design *bias, const std::string &bias_why,
                                             const DiagnoseOptions &opt, const DiagnoseReport &rep,
                                             std::vector<size_t> &selected) {
  const auto &table = candidate_table();
  std::vector<CandidateResult> res(table.size());
  std::vector<size_t> residual_family, rate_family, bias_family;
  for (size_t c = 0; c < table.size(); ++c) {
    res[c].key = table[c].key;
    const bool on_rates = table[c].rate_capable() && rates;
    const bool on_bias = table[c].needs == Needs::AccelBias && bias;
    (on_bias ? bias_family : on_rates ? rate_family : residual_family).push_back(c);
    res[c].description = on_rates ? table[c].rate_description : table[c].description;
    if (table[c].rate_capable() && !rates)
      res[c].note = "on the residual (" + rate_why + "): " + table[c].fallback_note;
  }
  selected = test_family(d, residual_family, false, false, bias_why, opt, rep, res);
  if (rates) {
    const auto sel_rate = test_family(*rates, rate_family, true, false, bias_why, opt, rep, res);
    selected.insert(selected.end(), sel_rate.begin(), sel_rate.end());
  }
  if (bias) {
    const auto sel_bias = test_family(*bias, bias_family, false, true, bias_why, opt, rep, res);
    selected.insert(selected.end(), sel_bias.begin(), sel_bias.end());
  }
  return res;
}

std::vector<CandidateResult> rank_candidates(std::vector<CandidateResult> res, const std::vector<size_t> &selected) {
  // The filter's accelerometer bias is downstream of every other effect: whatever the model lacks moves the state,
  // and the bias takes its share (a wandering offset and a readout time were named accelerometer scale first on the
  // sizing flights). The images-against-gyro and residual evidence never sees the accelerometer, so its selected
  // candidates come first; a bias candidate selected beside them says that its evidence may be their echo.
  const auto downstream = [](size_t c) { return candidate_table()[c].needs == Needs::AccelBias; };
  std::vector<size_t> order = selected;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    if (downstream(a) != downstream(b))
      return downstream(b);
    return res[a].explained_added > res[b].explained_added;
  });
  const bool upstream_selected = std::any_of(order.begin(), order.end(), [&](size_t c) { return !downstream(c); });
  for (size_t c : order)
    if (downstream(c) && upstream_selected)
      res[c].note = "ranked after the effects the images show: the filter's accelerometer bias also absorbs their "
                    "error; re-diagnose after modelling them" +
                    (res[c].note.empty() ? std::string() : "; " + res[c].note);
  std::vector<size_t> rest;
  for (size_t c = 0; c < res.size(); ++c)
    if (std::find(order.begin(), order.end(), c) == order.end())
      rest.push_back(c);
  std::stable_sort(rest.begin(), rest.end(), [&](size_t a, size_t b) {
    if (res[a].testable != res[b].testable) // what the log can resolve before what it cannot
      return res[a].testable;
    if ((res[a].sigma > 0) != (res[b].sigma > 0))
      return res[a].sigma > 0;
    if (res[a].explained_added != res[b].explained_added)
      return res[a].explained_added > res[b].explained_added;
    return res[a].explained_alone > res[b].explained_alone;
  });
  order.insert(order.end(), rest.begin(), rest.end());
  std::vector<CandidateResult> ranked;
  for (size_t r = 0; r < order.size(); ++r) {
    res[order[r]].rank = static_cast<int>(r + 1);
    ranked.push_back(res[order[r]]);
  }
  return ranked;
}

std::vector<TimeBin> offset_per_time_bin(const Design &dt, bool from_rates, const UsedData &data,
                                         const DiagnoseOptions &opt, const DiagnoseReport &rep) {
  std::vector<TimeBin> out;
  if (!dt.have_velocity)
    return out;
  const int bins = opt.time_bins;
  const Eigen::Index nt = dt.r.size();
  std::vector<int> bin_of(nt);
  for (Eigen::Index k2 = 0; k2 < nt; ++k2)
    bin_of[k2] = std::min(bins - 1, static_cast<int>(bins * dt.t_s[k2] / std::max(1e-9, rep.duration_s)));
  std::vector<double> td_sum(bins, 0.0);
  std::vector<long> td_cnt(bins, 0);
  for (const auto &kv : data.tracks)
    for (auto *r : kv.second) {
      const int b = std::min(bins - 1, static_cast<int>(bins * 1e-9 * double(r->t_cam_ns - data.t_first) /
                                                        std::max(1e-9, rep.duration_s)));
      td_sum[b] += r->td_s, ++td_cnt[b];
    }
  for (int b = 0; b < bins; ++b) {
    std::vector<char> mask(nt);
    long cnt = 0;
    for (Eigen::Index k2 = 0; k2 < nt; ++k2)
      cnt += (mask[k2] = bin_of[k2] == b);
    if (cnt < (from_rates ? 5 * kRateRowsPerImage : 40))
      continue;
    const Fit f = fit_cols(dt, {kV}, opt.huber_k, &mask);
    TimeBin tb;
    tb.t_s = (b + 0.5) * rep.duration_s / bins;
    tb.td_ms = 1e3 * f.beta(0);
    tb.td_se_ms = 1e3 * std::sqrt(std::max(0.0, f.cov(0, 0)));
    tb.td_filter_ms = td_cnt[b] ? 1e3 * td_sum[b] / td_cnt[b] : 0.0;
    tb.observations = from_rates ? cnt / kRateRowsPerImage : cnt / 2;
    out.push_back(tb);
  }
  return out;
}

} // namespace ovton::eval::diag
