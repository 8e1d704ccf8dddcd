#include "ov_msckf_ton/core/filter_health.h"
#include "ov_core/types/errors.h"
#include "ov_core/types/time.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ov_msckf_ton {

namespace {

/// " (at IMU time 12.345 s, t_d 10.000 ms)": where the run stopped, for the message.
std::string where(const State &s) {
  char buf[80];
  std::snprintf(buf, sizeof buf, " (at IMU time %.3f s, t_d %.3f ms)", ov_core::ns_to_s(s.t_imu_ns), s.td * 1e3);
  return buf;
}

} // namespace

FilterHealth::FilterHealth(const VioOptions &o) {
  opt_.enabled = o.health_checks;
  opt_.td_random_walk = uses_tpn(o.td_mode) ? o.td_random_walk_tpn : o.td_random_walk;
  opt_.td_rate_allowance = uses_tpn(o.td_mode) ? o.td_rate_max : 0.0;
}

void FilterHealth::on_update(const State &s, const UpdateStats &st) {
  Entry e{s.t_imu_ns, {}, s.td, s.estimates_td() ? s.P(s.td_index, s.td_index) : 0.0};
  e.tally.used = st.features_used;
  e.tally.gated = st.gated_chi2;
  e.tally.failed_triangulation = st.rejected_triangulation;
  total_.used += e.tally.used;
  total_.gated += e.tally.gated;
  total_.failed_triangulation += e.tally.failed_triangulation;
  recent_.push_back(e);
  const double keep_ns = std::max(opt_.window_s, opt_.td_window_s + opt_.td_persist_s) * 1e9 + 1e8;
  while (!recent_.empty() && static_cast<double>(s.t_imu_ns - recent_.front().t_ns) > keep_ns)
    recent_.pop_front();
}

UpdateTally FilterHealth::window() const {
  UpdateTally w;
  const int64_t newest = recent_.empty() ? 0 : recent_.back().t_ns;
  for (const auto &e : recent_) {
    if (static_cast<double>(newest - e.t_ns) > opt_.window_s * 1e9)
      continue;
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
    throw ov_core::EstimatorFailure(s.t_imu_ns, "the filter's " + bad + " is no longer finite" + where(s));
  if (!opt_.enabled)
    return;
  check_rates(s);
  check_td(s);
}

void FilterHealth::check_rates(const State &s) const {
  const UpdateTally w = window();
  if (w.examined() < opt_.min_features)
    return;
  char msg[512];
  if (w.acceptance() < opt_.min_acceptance) {
    std::snprintf(msg, sizeof msg,
                  "the estimate has diverged: over the last %.1f s only %ld of %ld features entered the update (%ld "
                  "failed triangulation, %ld failed the chi-square gate); a healthy run keeps ~90 %%",
                  opt_.window_s, w.used, w.examined(), w.failed_triangulation, w.gated);
    throw ov_core::EstimatorFailure(s.t_imu_ns, msg + where(s));
  }
  if (w.gate_rate() > opt_.max_gate_rate) {
    std::snprintf(msg, sizeof msg,
                  "the estimate is inconsistent with the images: over the last %.1f s the chi-square gate rejected "
                  "%ld of %ld triangulated features, where a 95 %% gate rejects 5 %% by chance",
                  opt_.window_s, w.gated, w.used + w.gated);
    throw ov_core::EstimatorFailure(s.t_imu_ns, msg + where(s));
  }
}

FilterHealth::TdStep FilterHealth::td_step(size_t end) const {
  // A consistent filter's estimate changes between two times by what its covariance lost in between (plus process
  // noise): the change has variance P(then) − P(now). "Then" is the newest update at least td_window_s older.
  TdStep r;
  const Entry &now = recent_[end];
  const Entry *then = nullptr;
  for (size_t i = 0; i < end; ++i)
    if (static_cast<double>(now.t_ns - recent_[i].t_ns) >= opt_.td_window_s * 1e9)
      then = &recent_[i];
  if (!then)
    return r;
  r.dt = ov_core::ns_to_s(now.t_ns - then->t_ns);
  r.moved = std::abs(now.td - then->td);
  r.step = r.moved - opt_.td_rate_allowance * r.dt;
  r.allowed = std::sqrt(std::max(0.0, then->td_var - now.td_var) + opt_.td_random_walk * opt_.td_random_walk * r.dt);
  return r;
}

void FilterHealth::check_td(const State &s) const {
  if (!s.estimates_td() || recent_.size() < 2)
    return;
  const auto runaway = [&](const TdStep &st) {
    return st.step > opt_.td_min_step_s && st.step > opt_.td_max_z * std::max(st.allowed, 1e-9);
  };
  const TdStep now = td_step(recent_.size() - 1);
  if (!runaway(now))
    return;
  // The same a second earlier: a sustained walk, not the one-off jump of a filter converging from far off.
  size_t earlier = recent_.size() - 1;
  while (earlier > 0 && static_cast<double>(recent_.back().t_ns - recent_[earlier].t_ns) < opt_.td_persist_s * 1e9)
    --earlier;
  if (!runaway(td_step(earlier)))
    return;
  char msg[400];
  std::snprintf(msg, sizeof msg,
                "the time offset is running away: t_d moved %.1f ms in %.1f s where its covariance allowed %.2f ms "
                "(%.0f sigma), and as much the second before - a diverging estimate, not a measurement",
                now.moved * 1e3, now.dt, now.allowed * 1e3, now.step / std::max(now.allowed, 1e-9));
  throw ov_core::EstimatorFailure(s.t_imu_ns, msg + where(s));
}

} // namespace ov_msckf_ton
