#pragma once
// Health of the running filter: the checks that turn a diverged estimate into an error instead of rows that look like
// an answer (docs/robustness.md has the measurements behind each threshold):
//  - a non-finite state or covariance;
//  - a collapsed update acceptance: a filter started 100-150 ms from the true offset on rendered V1_02 flights keeps
//    fewer than 5 % of the features its updates examine (triangulation fails, the gate rejects), from the first
//    second on, while t_d's sigma keeps shrinking; healthy runs keep ~90 %;
//  - a gate rate far beyond chance: a 95 % chi-square gate rejects 5 % of consistent features;
//  - t_d running away from its own uncertainty: the image-plane modes on a fast start walked from 10 to 80-98 ms with
//    sigma 0.2-0.4 ms, moving 8-15 ms in 2 s where their covariance allowed < 0.4 ms (14-117 sigma, for seconds on
//    end); sr converging from 50 ms off on rendered V1_02 jumped ~11 sigma in one window (an over-confident but
//    right estimate), so the step must exceed 15 sigma in two windows a second apart.
#include "ov_msckf_ton/core/vio_options.h"
#include "ov_msckf_ton/state/state.h"
#include "ov_msckf_ton/update/updater_msckf.h"

#include <cstdint>
#include <deque>
#include <string>

namespace ov_msckf_ton {

struct FilterHealthOptions {
  bool enabled = true;          ///< false: only count (VioOptions::health_checks)
  double window_s = 3.0;        ///< acceptance and gate rate are judged over the updates of this last stretch
  int min_features = 60;        ///< features examined in the window before a rate is judged (fewer say little)
  double min_acceptance = 0.25; ///< used / examined (triangulation failures included)
  /// gated / (used + gated): ten times what a 95 % gate rejects by chance; over 60+ features no consistent filter
  /// gets there (binomial tail < 1e-30).
  double max_gate_rate = 0.5;
  double td_window_s = 2.0;    ///< t_d's change is judged over this lag
  double td_persist_s = 1.0;   ///< ... in the window ending now and in the one ending this much earlier
  double td_min_step_s = 2e-3; ///< changes below this are never a runaway
  /// change / sqrt(variance gained + process noise) above this, in both windows, is one. sr converging from 50 ms off
  /// reached 11 (a jump, in one window); the runaways 14-117, for seconds.
  double td_max_z = 15.0;
  double td_random_walk = 0.0;    ///< s/sqrt(s): process noise the change may use
  double td_rate_allowance = 0.0; ///< s/s: drift a mode may impose on the mean (TPN's clamp)
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
  /// Thresholds as above, process noise and drift allowance of the options' mode, enabled by health_checks.
  explicit FilterHealth(const VioOptions &opt);

  /// After each MSCKF update at the state's time, with the state after it.
  void on_update(const State &s, const UpdateStats &st);
  /// Before a state is handed out. Throws ov_core::EstimatorFailure saying what went wrong when the state or its
  /// covariance is not finite, the last window's acceptance collapsed or its gate rate is far beyond chance, or t_d
  /// moved far more than its covariance allows.
  void check(const State &s) const;

  const UpdateTally &total() const { return total_; }
  /// The tally of the current window (the last window_s seconds of updates).
  UpdateTally window() const;
  /// "" when every estimated quantity is finite and the covariance diagonal non-negative, else what is not.
  static std::string nonfinite_part(const State &s);

private:
  struct Entry {
    int64_t t_ns;
    UpdateTally tally;
    double td, td_var;
  };
  void check_rates(const State &s) const;
  void check_td(const State &s) const;
  /// t_d's change over the td_window_s before recent_[end] beyond the mode's drift allowance, and what its covariance
  /// and process noise allowed (both 0 when the history is too short).
  struct TdStep {
    double step = 0, allowed = 0, moved = 0, dt = 0;
  };
  TdStep td_step(size_t end) const;

  FilterHealthOptions opt_;
  std::deque<Entry> recent_; ///< the last max(window_s, td_window_s + td_persist_s) seconds of updates
  UpdateTally total_;
};

} // namespace ov_msckf_ton
