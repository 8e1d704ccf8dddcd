#include "ov_msckf_ton/core/filter_health.h"
#include "ov_core/types/errors.h"
#include "ov_core/types/time.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ovton::msckf {

namespace {

/// " (at IMU time 12.345 s, t_d 10.000 ms)": where the run stopped, for the message.
std::string where(const State &s) {
  char buf[80];
  std::snprintf(buf, sizeof buf, " (at IMU time %.3f s, t_d %.3f ms)", ovton::core::ns_to_s(s.t_imu_ns), s.td * 1e3);
  return buf;
}

} // namespace

FilterHealth::FilterHealth(const VioOptions &o) : FilterHealth() {
  opt_.enabled = o.health.enabled;
}

void FilterHealth::on_update(int64_t t_ns, const UpdateStats &st) {
  Tally e{t_ns, {}};
  e.tally.used = st.features_used;
  e.tally.gated = st.gated_chi2;
  // Too little parallax is not a failure: a vehicle standing still (EuRoC's machine-hall starts) triangulates nothing
  // and is not diverging. Those features are left out of the rates altogether.
  e.tally.failed_triangulation = st.rejected_triangulation - st.low_parallax;
  total_.used += e.tally.used;
  total_.gated += e.tally.gated;
  total_.failed_triangulation += e.tally.failed_triangulation;
  recent_.push_back(e);
  while (!recent_.empty() && static_cast<double>(t_ns - recent_.front().t_ns) > opt_.window_s * 1e9)
    recent_.pop_front();
}

void FilterHealth::on_td_update(int64_t t_ns, double td_prior, double var_prior, double td_post, double var_post) {
  corrections_.add(t_ns, td_prior, var_prior, td_post, var_post);
}

UpdateTally FilterHealth::window() const {
  UpdateTally w;
  for (const auto &e : recent_) {
    w.used += e.tally.used;
    w.gated += e.tally.gated;
    w.failed_triangulation += e.tally.failed_triangulation;
  }
  return w;
}

std::string FilterHealth::nonfinite_part(const State &s) {
  if (!s.imu.R.allFinite() || !s.imu.p.allFinite() || !s.imu.v.allFinite())
    return "IMU pose or velocity";
  if (!s.imu.bg.allFinite() || !s.imu.ba.allFinite())
    return "IMU biases";
  if (!std::isfinite(s.td))
    return "time offset t_d";
  for (const auto &[t, c] : s.clones)
    if (!c.R.allFinite() || !c.p.allFinite())
      return "cloned pose at camera time " + std::to_string(t) + " ns";
  if (!s.P.allFinite())
    return "covariance";
  if (s.separate_report() && !s.P_report.allFinite())
    return "reported covariance";
  // Rounding leaves tiny negative variances after long runs; a clearly negative one means the covariance is broken.
  for (int i = 0; i < s.dim(); ++i)
    if (s.P(i, i) < -1e-9)
      return "covariance (negative variance at index " + std::to_string(i) + ")";
  return "";
}

void FilterHealth::check(const State &s) const {
  // A non-finite state is never worth a row, checks enabled or not.
  const std::string bad = nonfinite_part(s);
  if (!bad.empty())
    throw ovton::core::EstimatorFailure(s.t_imu_ns, "the filter's " + bad + " is no longer finite" + where(s));
  if (!opt_.enabled)
    return;
  check_rates(s);
  check_td(s);
}

void FilterHealth::check_rates(const State &s) const {
  const UpdateTally w = window();
  if (w.examined() < opt_.min_features)
    return;
  char msg[700];
  if (w.acceptance() < opt_.min_acceptance) {
    std::snprintf(msg, sizeof msg,
                  "the estimate has diverged: over the last %.1f s only %ld of %ld features entered the update (%ld "
                  "failed triangulation, %ld failed the chi-square gate); a healthy run keeps ~90 %%",
                  opt_.window_s, w.used, w.examined(), w.failed_triangulation, w.gated);
    throw ovton::core::EstimatorFailure(s.t_imu_ns, msg + where(s));
  }
  if (w.gate_rate() > opt_.max_gate_rate) {
    // What the user can do about it: name the usual causes. On whole rendered flights with a drifting offset `sr`
    // and `sir` stop here (docs/ton.md, "Table III on whole flights") while the modes that let t_d move finish.
    std::snprintf(msg, sizeof msg,
                  "the estimate is inconsistent with the images: over the last %.1f s the chi-square gate rejected "
                  "%ld of %ld triangulated features, where a 95 %% gate rejects 5 %% by chance - the model lacks "
                  "something the images show: e.g. a time offset that drifts (modes drift and sr+random_walk let t_d "
                  "move), a rolling shutter, a calibration error or understated noise (`ovton diagnose` on a "
                  "--residual-log of this run ranks what could explain it)",
                  opt_.window_s, w.gated, w.used + w.gated);
    throw ovton::core::EstimatorFailure(s.t_imu_ns, msg + where(s));
  }
}

void FilterHealth::check_td(const State &s) const {
  if (!s.estimates_td() || corrections_.empty())
    return;
  const auto runaway = [&](const TdCorrectionWindow::Sum &t) {
    const double moved = std::abs(t.moved);
    return t.covered && moved > opt_.td_min_step_s && moved > opt_.td_max_z * std::sqrt(t.allowed_var);
  };
  const int64_t now_ns = corrections_.last_ns();
  const TdCorrectionWindow::Sum now = corrections_.sum(now_ns, opt_.td_window_s);
  // The same a second earlier: a sustained walk, not the one-off jump of a filter converging from far off.
  if (!runaway(now) ||
      !runaway(corrections_.sum(now_ns - static_cast<int64_t>(opt_.td_persist_s * 1e9), opt_.td_window_s)))
    return;
  // Both readings are named: the paper's modes diverging on a fast start look like this, and so does `sr` following an
  // offset that really wanders (diagnose_sizing.sh's wandering offset stopped two of four flights here).
  char msg[600];
  std::snprintf(msg, sizeof msg,
                "the time offset is running away: the updates moved t_d by %.1f ms in %.1f s where the information "
                "they added allowed %.2f ms (%.0f sigma), and as much the second before - either the estimate "
                "diverges or the true offset varies faster than this mode's t_d model lets it (`ovton diagnose` on a "
                "--residual-log of this run tells which; modes drift and sr+random_walk let t_d move)",
                now.moved * 1e3, opt_.td_window_s, std::sqrt(now.allowed_var) * 1e3,
                std::abs(now.moved) / std::max(std::sqrt(now.allowed_var), 1e-12));
  throw ovton::core::EstimatorFailure(s.t_imu_ns, msg + where(s));
}

} // namespace ovton::msckf
