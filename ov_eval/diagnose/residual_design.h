#pragma once
// The design on the residual (docs/diagnose.md, "Data used" and "Point projection"): two rows per observation, the
// residual r = (res_u_px, res_v_px) and what each candidate would produce there, built from the filter's predicted
// observations; residual and columns are projected onto what the track's triangulated point cannot absorb.
#include "ov_eval/diagnose/regression.h"
#include "ov_eval/diagnose/tracks.h"

namespace ovton::eval::diag {

/// Clustered by track. Fills rep.residual_rms_px and rep.robust_sigma_px (rep's intrinsics and image height must be
/// set).
Design build_residual_design(const UsedData &data, const DiagnoseOptions &opt, DiagnoseReport &rep);

} // namespace ovton::eval::diag
