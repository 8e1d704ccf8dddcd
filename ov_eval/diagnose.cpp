// `ovton diagnose` as the list of its stages; each stage is a file in ov_eval/diagnose/ (docs/diagnose.md).
#include "ov_eval/diagnose.h"
#include "ov_core/types/errors.h"
#include "ov_eval/diagnose/accel_design.h"
#include "ov_eval/diagnose/candidates.h"
#include "ov_eval/diagnose/focal_two_view.h"
#include "ov_eval/diagnose/rate_design.h"
#include "ov_eval/diagnose/residual_design.h"
#include "ov_eval/diagnose/selection.h"
#include "ov_eval/diagnose/tracks.h"
#include "ov_eval/diagnose/unexplained.h"
#include <algorithm>

namespace ovton::eval {

DiagnoseReport diagnose(const ResidualLog &log, const DiagnoseOptions &opt) {
  if (!(opt.min_sigma > 0) || !(opt.min_explained >= 0) || !(opt.huber_k > 0) || opt.time_bins < 1 || opt.plot_bins < 2)
    throw ovton::core::UsageError("diagnose: thresholds must be positive and bins at least 1 (time) / 2 (plots)");
  DiagnoseReport rep;
  rep.log_file = log.file;
  rep.options = opt;
  rep.rows_read = static_cast<long>(log.rows.size());

  // 1. The rows with a residual, in tracks of 3+; the camera's intrinsics and image height.
  const diag::UsedData data = diag::select_data(log, opt, rep);
  if (data.observations < diag::kMinObservations) {
    // A log of a platform that did not move (the filter made ZUPTs, no feature update) or of a run too short: valid,
    // and nothing in it can show an effect. A verdict, not an error.
    if (opt.have_camera || (opt.fu > 0 && opt.fv > 0)) // given, not fitted: there are no rows to fit them from
      diag::set_intrinsics(data, opt, log.file, rep);
    rep.not_testable = "only " + std::to_string(data.observations) +
                       " usable observations (accepted or gated, in tracks of 3+): no feature update to test (a "
                       "platform that did not move, or a run too short)";
    for (size_t c = 0; c < diag::candidate_table().size(); ++c) {
      CandidateResult cr;
      cr.key = diag::candidate_table()[c].key;
      cr.description = diag::candidate_table()[c].description;
      cr.testable = false;
      cr.rank = static_cast<int>(c + 1);
      cr.note = "not testable on this log";
      rep.candidates.push_back(cr);
    }
    return rep;
  }
  diag::set_intrinsics(data, opt, log.file, rep);

  // 2. The residual design: every candidate's effect on the residual, what the tracks' points absorb projected out.
  const diag::Design d = diag::build_residual_design(data, opt, rep);

  // 3. The rate design. A time-offset error is a per-frame pose change, which a filter whose poses follow the images
  // absorbs (docs/diagnose.md), so with the raw gyro at hand the candidates a filter's state absorbs are tested on the
  // camera's angular rate seen in the images against the gyro's, not on the residual.
  diag::Design dr;
  std::string rate_why = "no raw gyro (pass --dataset)";
  rep.time_from_rates = !opt.imu.empty() && opt.have_camera && diag::build_rate_design(data, opt, rep, dr, rate_why);

  // 3b. The filter's accelerometer bias against the specific force: an accelerometer scale no image shows.
  diag::Design db;
  std::string bias_why;
  const bool have_bias = diag::build_accel_design(data, opt, rep, db, bias_why);

  // 4. Stepwise selection in each family, then the ranking.
  std::vector<size_t> selected;
  auto results = diag::test_candidates(d, rep.time_from_rates ? &dr : nullptr, rate_why, have_bias ? &db : nullptr,
                                       bias_why, opt, rep, selected);
  // The inputs of the rates or of the accelerometer's design are there but the log is too short for it: a limit of
  // this log, not a missing input.
  const bool rates_short = !rep.time_from_rates && !opt.imu.empty() && opt.have_camera;
  const bool accel_short = !have_bias && !opt.calibration.empty() && !opt.imu.empty();
  for (size_t c = 0; c < results.size(); ++c) { // results follow the candidate table
    const diag::Needs needs = diag::candidate_table()[c].needs;
    if ((rates_short && needs == diag::Needs::Rates) || (accel_short && needs == diag::Needs::AccelBias)) {
      results[c].testable = false;
      results[c].note = "not testable on this log: " + (needs == diag::Needs::Rates ? rate_why : bias_why);
    }
  }
  rep.candidates = diag::rank_candidates(results, selected);

  // 4b. A focal error the rates name is sized from two views and the gyro, with the focal in the model while the
  // depths are fitted (focal_two_view.h): the rates' column reads it low.
  for (CandidateResult &c : rep.candidates)
    if (c.key == "focal" && c.explained && rep.time_from_rates)
      diag::size_focal_from_two_views(data, opt, rep, c);

  // 5. What the residual keeps beyond its noise that no selected candidate explains, and where it shows.
  {
    std::vector<int> cols;
    for (size_t c : selected)
      if (results[c].explained && !(rep.time_from_rates && diag::candidate_table()[c].rate_capable()) &&
          diag::candidate_table()[c].needs != diag::Needs::AccelBias)
        for (int col : diag::candidate_table()[c].columns(opt.have_camera))
          if (std::find(cols.begin(), cols.end(), col) == cols.end())
            cols.push_back(col);
    rep.unexplained = diag::find_unexplained(d, cols, opt, rep);
  }

  // 6. The offset error per time bin, on the design the time candidates were tested on.
  rep.td_bins = diag::offset_per_time_bin(rep.time_from_rates ? dr : d, rep.time_from_rates, data, opt, rep);
  return rep;
}

} // namespace ovton::eval
