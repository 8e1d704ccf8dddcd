#pragma once
// The time offset's model checks itself. Under a right model the corrections the updates make to t_d sum, over any
// stretch, to about the sigma the updates' information allows (td_correction_window.h). A constant (or TPN's) model
// on an offset that drifts faster than it allows is corrected the same way image after image: the sum grows
// linearly with the stretch while its sigma shrinks, the estimate trails the offset and the filter's sigma says it
// does not. When the sums over two stretches in a row exceed time_offset.model_check_z sigmas, the check hands t_d
// to the drift state (td_drift.cpp: the rate becomes a state variable, so the updates estimate how fast t_d moves)
// and widens t_d's variance by what the corrections showed the estimate trails by. It says so once: the run's
// summary names the time and the sums (TdModelStats::switched_ns).
#include "ov_msckf_ton/td/td_correction_window.h"
#include "ov_msckf_ton/td/td_model.h"

#include <cstdint>
#include <memory>
#include <string>

namespace ovton::msckf {

/// The test alone, apart from the state it guards (so that a sequence of corrections can be tested by itself).
class TdTrendTest {
public:
  struct Verdict {
    bool contradicted = false; ///< both stretches beyond z sigmas and min_step, with one sign
    double z = 0.0;            ///< the smaller of the two stretches' sums in sigmas
    double moved_s = 0.0;      ///< what the corrections moved t_d by over both stretches [s]
  };
  TdTrendTest(double window_s, double z, double min_step_s);
  /// One update's t_d mean and variance before and after, at IMU time t_ns.
  void add(int64_t t_ns, double td_prior, double var_prior, double td_post, double var_post);
  /// The two stretches of window_s ending at the last correction.
  Verdict evaluate() const;

private:
  double window_s_, z_, min_step_s_;
  TdCorrectionWindow window_;
};

/// `inner` with the check around it; the inner model runs unchanged until the check fires.
std::unique_ptr<TdModel> make_checked_model(std::unique_ptr<TdModel> inner, const TimeOffsetOptions &o);
/// The model a checked model wraps (itself for any other model).
const TdModel &unchecked_model(const TdModel &m);
/// The line a run's summary (ovton run, ovton compare's notes) says the switch with: "t_d model check: switched to the
/// drift state at T s; ..." with T from `first_ns` (the run's first row); "" when the check did not switch.
std::string describe_model_check(const TdModelStats &st, int64_t first_ns, const TimeOffsetOptions &o);

} // namespace ovton::msckf
