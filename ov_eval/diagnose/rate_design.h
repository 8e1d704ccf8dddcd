#pragma once
// The design on rates (docs/diagnose.md, "Two kinds of evidence"): the effects a filter's state absorbs from its
// residual (time offset, rolling-shutter readout, focal error, gyro scale) tested on the camera's angular rate seen in
// the images against the raw gyro's, which no state of the filter can make disagree.
#include "ov_eval/diagnose/regression.h"
#include "ov_eval/diagnose/tracks.h"

#include <string>

namespace ovton::eval::diag {

/// Rows of the rate design per image: ω_vis − ω̄_gyro (the gyro through the images' estimator) and ψ_vis, three axes
/// each.
constexpr int kRateRowsPerImage = 6;

/// Per image, the measured image velocities of its features (their depths corrected per track) are fitted with the
/// flow model ẋ = B(x)·(ω + ρ·ψ) + A(x)·v/z, ρ the row fraction − ½: ω is the camera's angular rate seen at the
/// image's middle row, ψ its change from the top row to the bottom one. kRateRowsPerImage rows per image, whitened
/// per axis by the fit's standard errors, clustered per quarter second:
///  - ω_vis − ω̄_gyro, ω̄_gyro the gyro put through the images' estimator at the filter's image times t_cam + t̂_d (the
///    same slopes, the same fit), the gyro bias b removed per 5-s bin. On these rows, jointly: a time-offset error
///    δt = t_d − t̂_d shows as α·δt, α the gyro through the images' slope (GyroSlope in the .cpp: a difference of the
///    raw gyro carries its vibration into the regressor, which scales an estimate down); a readout t_r as
///    psi_resp·α·t_r (ω is fitted at the features' mean row); a relative focal error ε through ω_vis's response to ε
///    (the whole fit); the gyro's scale, misalignment and a camera-body rotation through ω̄_gyro.
///  - ψ_vis: a rolling shutter exposes row ρ at (ρ + ½)·t_r after row 0, so the rate changes down the image by
///    ψ = α·t_r. Nothing in a filter's state can produce it.
/// Measured image velocities (not predicted ones) keep the filter's state out of it. Needs opt.camera and opt.imu.
/// Returns false, with the reason in `why`, when fewer than 50 images have 12+ features of known depth.
bool build_rate_design(const UsedData &data, const DiagnoseOptions &opt, const DiagnoseReport &rep, Design &dr,
                       std::string &why);

} // namespace ovton::eval::diag
