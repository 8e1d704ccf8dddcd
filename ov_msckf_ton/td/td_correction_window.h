#pragma once
// The corrections the updates made to t_d, kept over a sliding stretch of time: what a consistent filter's t_d
// corrections can add up to is known from its own covariance. Over any stretch, the sum of the corrections Σδ has
// variance Σ(P⁻ − P⁺), the variance the updates took off (white innovations make the corrections uncorrelated). A sum
// many times that sigma means t_d moves in a way the filter's model of it does not allow: the model check
// (td_model_check.h) switches the model, the health check (filter_health.h) stops a run that runs away.
#include <cstdint>
#include <deque>

namespace ovton::msckf {

class TdCorrectionWindow {
public:
  /// The sum over one stretch: the corrections' sum and the variance they took off.
  struct Sum {
    double moved = 0.0, allowed_var = 0.0;
    bool covered = false; ///< the corrections reach back over the whole stretch
    /// |moved| in sigmas of what the updates allowed (0 for a stretch without information).
    double z() const;
  };

  /// keep_s: how far back sums can reach.
  explicit TdCorrectionWindow(double keep_s) : keep_ns_(static_cast<int64_t>(keep_s * 1e9)) {}

  /// One update's t_d mean and variance before and after, at IMU time t_ns.
  void add(int64_t t_ns, double td_prior, double var_prior, double td_post, double var_post);
  /// The corrections over (end_ns − window_s, end_ns].
  Sum sum(int64_t end_ns, double window_s) const;
  bool empty() const { return corrections_.empty(); }
  int64_t last_ns() const { return corrections_.back().t_ns; }
  /// Forgets every correction (a model switch starts a new history).
  void clear();

private:
  struct Correction {
    int64_t t_ns;
    double delta, var_drop;
  };
  int64_t keep_ns_;
  std::deque<Correction> corrections_;
  int64_t first_ns_ = -1;
};

} // namespace ovton::msckf
