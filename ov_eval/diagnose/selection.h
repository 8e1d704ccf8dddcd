#pragma once
// The last stages of `ovton diagnose`: every candidate of the table tested on its design by stepwise selection,
// the ranking, and the offset error per time bin (docs/diagnose.md, "Estimation and verdict").
#include "ov_eval/diagnose.h"
#include "ov_eval/diagnose/regression.h"
#include "ov_eval/diagnose/tracks.h"

#include <string>
#include <vector>

namespace ovton::eval::diag {

/// Candidates tested on the residual design d and, when `rates` is given, those that can be on the rate design (the
/// others stay on d; rate_why says why there are no rates), and when `bias` is given the accelerometer's on the
/// filter's bias (accel_design.h; skipped otherwise). Returns one result per candidate of candidate_table(), in its
/// order; `selected` gets the selected ones (residual family first, then rates, then bias, each in selection order).
std::vector<CandidateResult> test_candidates(const Design &d, const Design *rates, const std::string &rate_why,
                                             const Design *bias, const std::string &bias_why,
                                             const DiagnoseOptions &opt, const DiagnoseReport &rep,
                                             std::vector<size_t> &selected);

/// The selected candidates by the share they explain of their own data — those on the filter's accelerometer bias
/// after the others, whose error that bias also absorbs — then the rest (testable before not testable, tested before
/// untested, then by share); sets
/// each rank.
std::vector<CandidateResult> rank_candidates(std::vector<CandidateResult> res, const std::vector<size_t> &selected);

/// δt per time bin (the trend a drift shows), each bin fitted on its own rows of dt (kV only, nothing else removed),
/// with the filter's mean t̂_d in the bin. Empty when dt has no velocity.
std::vector<TimeBin> offset_per_time_bin(const Design &dt, bool from_rates, const UsedData &data,
                                         const DiagnoseOptions &opt, const DiagnoseReport &rep);

} // namespace ovton::eval::diag
