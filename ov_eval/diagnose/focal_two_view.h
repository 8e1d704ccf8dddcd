#pragma once
// The size of a focal error from two views and the gyro (docs/diagnose.md, "A focal error from two views and the
// gyro"). The rates' focal column names a focal error reliably but reads it low (0.58-1.01 % for 1 % on the sizing
// flights): the per-track depth corrections, fitted without the focal in the model, take part of it up. Here the focal
// error ε is in the model while the depths are fitted: every pair of consecutive observations of a track, the camera's
// rotation between them from the gyro, the point at the filter's inverse depth times a per-track factor, a translation
// per image pair, the second observation predicted exactly (x' = π(Rᵀ·(P − t))) after moving the measured points by
// −ε·s(x) (s: focal_dir) and the prediction back by +ε·s; for each ε the depths and translations are refitted
// (Gauss-Newton alternation, Huber weights) and ε̂ is the minimum of the profile.
#include "ov_eval/diagnose/tracks.h"

#include <string>

namespace ovton::eval::diag {

struct TwoViewFocal {
  bool ok = false;
  double eps = 0, se = 0; ///< relative focal error and its standard error (scores clustered per track)
  long pairs = 0;         ///< observation pairs used
  std::string why;        ///< when not ok
};

/// Needs opt.camera, opt.imu and 200 observation pairs; the gyro bias, D_w and R_BC from the filter's calibration log
/// when there is one. `centre` is where the profile's grid is centred (the rates' estimate), ±2 % around it.
TwoViewFocal focal_two_view(const UsedData &data, const DiagnoseOptions &opt, double centre);

/// The focal candidate's estimates (ε and δf) from focal_two_view, centred on the rates' ε; the rates' reading kept as
/// "relative focal error ε (rates)". Left as it is, with a note, when the two views cannot size it.
void size_focal_from_two_views(const UsedData &data, const DiagnoseOptions &opt, const DiagnoseReport &rep,
                               CandidateResult &focal);

} // namespace ovton::eval::diag
