#pragma once
// Scores the image velocities of a velocity log (ov_core/io/velocity_log.h) against the truth: each track is
// triangulated from the ground-truth camera poses (at t_cam + t_d,true), and its true velocity at an observation is
// the time derivative of that point's projection along the ground-truth motion. Works on any folder with full-pose
// ground truth: simulated (exact poses) or real EuRoC (Vicon, ~1 mm / ~1°: a floor of a few px/s).
#include "ov_core/io/dataset.h"
#include "ov_core/io/velocity_log.h"

#include <string>
#include <vector>

namespace ovton::eval {

struct VelocityScore {
  std::string observations; ///< "first" (a new feature's first observation) or "tracked"
  std::string rule;         ///< eq2, next, its_fvon, f2f_fvon, used (what the filter's update used)
  long count = 0;
  double rms_px_s = 0, median_px_s = 0, true_rms_px_s = 0; ///< error RMS / median, and the true speeds' RMS
  double within_gate = 0;                                  ///< share with error below the gate
};

struct VelocityEvalResult {
  long rows = 0, features = 0, features_scored = 0;
  long first_observations = 0;
  long fvon_predictions = 0, fvon_gated = 0; ///< FVON's chosen predictions and how many failed the filter's gate
  std::vector<VelocityScore> scores;
};

struct VelocityEvalOptions {
  double gate_px_s = 80.0;    ///< the "within" threshold (the filter's FVON gate)
  double max_reproj_px = 2.0; ///< tracks whose truth-pose triangulation reprojects worse are left out
  double min_depth_m = 0.1;
};

/// Throws ovton::core::UsageError when the dataset has no full-pose ground truth.
VelocityEvalResult evaluate_velocities(const std::vector<ovton::core::VelocityLogRow> &rows,
                                       const ovton::core::Dataset &data, const VelocityEvalOptions &opt = {});

/// Markdown table of the scores.
std::string velocity_table(const VelocityEvalResult &r);

} // namespace ovton::eval
