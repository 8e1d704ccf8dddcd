#pragma once
// Health of the running filter: the checks that turn a diverged estimate into an error instead of rows that look like
// an answer (docs/robustness.md has the measurements behind each threshold):
//  - a non-finite state or covariance;
//  - a collapsed update acceptance: a filter started 100-150 ms from the true offset on rendered V1_02 flights keeps
//    fewer than 5 % of the features its updates examine (triangulation fails, the gate rejects), from the first
//    second on, while t_d's sigma keeps shrinking; healthy runs keep ~90 %;
//  - a gate rate far beyond chance: a 95 % chi-square gate rejects 5 % of consistent features;
//  - t_d running away from its own uncertainty. In a consistent filter the corrections the updates make to t_d are
//    martingale increments: their sum over a stretch has the variance those updates took off t_d's covariance. The
//    paper's image-plane modes on a fast start walked from 10 to 80-98 ms with sigma 0.2-0.4 ms, moving 8-15 ms in
//    2 s where their updates allowed < 0.4 ms (14-117 sigma, for seconds on end); sr converging from 50 ms off on a
//    rendered V1_02 flight jumped ~11 sigma in one window (over-confident, but right), so the sum must exceed 15 sigma
//    in two windows a second apart. What the t_d model does between updates (TPN's drive, the drift state, process
//    noise) is not an update's correction and does not count.
#include "ov_msckf_ton/core/vio_options.h"
#include "ov_msckf_ton/state/state.h"
#include "ov_msckf_ton/td/td_correction_window.h"
#include "ov_msckf_ton/update/updater_msckf.h"

#include <cstdint>
#include <deque>
#include <string>

namespace ovton::msckf {

struct FilterHealthOptions {
  bool enabled = true;          ///< false: only count (VioOptions::health)
  double window_s = 3.0;        ///< acceptance and gate rate are judged over the updates of this last stretch
  int min_features = 60;        ///< features examined in the window before a rate is judged (fewer say little)
  double min_acceptance = 0.25; ///< used / examined (triangulation failures included, too little parallax not)
  /// gated / (used + gated): ten times what a 95 % gate rejects by chance; over 60+ features no consistent filter
  /// gets there (binomial tail < 1e-30).
  double max_gate_rate = 0.5;
  double td_window_s = 2.0;    ///< t_d's corrections are summed over this stretch
  double td_persist_s = 1.0;   ///< ... ending now and ending this much earlier
  double td_min_step_s = 2e-3; ///< sums below this are never a runaway
  double td_max_z = 15.0;      ///< |sum| / sqrt(variance the updates took off) above this, in both windows, is one
};

/// Counts of one stretch of updates.
struct UpdateTally {
  long used = 0, gated = 0, failed_triangulation = 0;
  long examined() const { return used + gated + failed_triangulation; }
  double acceptance() const { return examined() > 0 ? static_cast<double>(used) / examined() : 1.0; }
  double gate_rate() const { return used + gated > 0 ? static_cast<double>(gated) / (used + gated) : 0.0; }
};

class FilterHealth {
public:
  explicit FilterHealth(const FilterHealthOptions &opt = {}) : opt_(opt) {}
  /// The thresholds above, enabled by the options' health.enabled.
  explicit FilterHealth(const VioOptions &opt);

  /// After each MSCKF update, at the state's IMU-clock time.
  void on_update(int64_t t_ns, const UpdateStats &st);
  /// After each EKF update (MSCKF, SLAM): t_d's mean and variance before and after it.
  void on_td_update(int64_t t_ns, double td_prior, double var_prior, double td_post, double var_post);
  /// Before a state is handed out. Throws ovton::core::EstimatorFailure saying what went wrong when the state or its
  /// covariance is not finite, the last window's acceptance collapsed or its gate rate is far beyond chance, or the
  /// updates moved t_d far more than they allowed.
  void check(const State &s) const;

  const UpdateTally &total() const { return total_; }
  /// The tally of the current window (the last window_s seconds of updates).
  UpdateTally window() const;
  /// "" when every estimated quantity is finite and the covariance diagonal non-negative, else what is not.
  static std::string nonfinite_part(const State &s);

private:
  void check_rates(const State &s) const;
  void check_td(const State &s) const;

  struct Tally {
    int64_t t_ns;
    UpdateTally tally;
  };
  FilterHealthOptions opt_;
  std::deque<Tally> recent_;                                             ///< the last window_s seconds of MSCKF updates
  TdCorrectionWindow corrections_{opt_.td_window_s + opt_.td_persist_s}; ///< t_d's corrections, as far back as read
  UpdateTally total_;
};

} // namespace ovton::msckf
