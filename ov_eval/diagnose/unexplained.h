#pragma once
// The "unexplained" verdict of `ovton diagnose`: structure the residual keeps beyond its noise after the selected
// candidates, which none of them models. The leftover is binned by where it could show - time, image region, image
// speed - and the bin means (u and v apart) are tested as a candidate would be: Wald σ with the residual's clustered
// sandwich (per quarter second of updates) and the share of the leftover's loss they remove, against the same bars
// (docs/diagnose.md). More bin means than the log's independent clusters: not testable on it.
#include "ov_eval/diagnose.h"
#include "ov_eval/diagnose/regression.h"

#include <vector>

namespace ovton::eval::diag {

/// `selected_cols`: the columns of the candidates selected on d. Rows without a region (−1) are left out of the
/// region test.
std::vector<UnexplainedStructure> find_unexplained(const Design &d, const std::vector<int> &selected_cols,
                                                   const DiagnoseOptions &opt, const DiagnoseReport &rep);

} // namespace ovton::eval::diag
