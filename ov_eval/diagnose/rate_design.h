#pragma once
// The design on rates (docs/diagnose.md, "Two kinds of evidence"): the effects a filter's state absorbs from its
// residual (time offset, rolling-shutter readout, focal error, gyro scale) tested on the camera's angular rate seen in
// the images against the raw gyro's, which no state of the filter can make disagree.
#include "ov_eval/diagnose/regression.h"
#include "ov_eval/diagnose/tracks.h"

#include <string>

namespace ov_eval::diag {

/// Rows of the rate design per image: ω_vis − ω_gyro, ψ_vis and ω_vis − ω̄_gyro (the gyro through the images'
/// estimator), three axes each.
constexpr int kRateRowsPerImage = 9;

/// Per image, the measured image velocities of its features (their depths corrected per track) are fitted with the
/// flow model ẋ = B(x)·(ω + ρ·ψ) + A(x)·v/z, ρ the row fraction − ½: ω is the camera's angular rate seen at the
/// image's middle row, ψ its change from the top row to the bottom one. kRateRowsPerImage rows per image, whitened
/// per axis by the fit's standard errors, clustered per second:
///  - ω_vis − ω_gyro at the filter's image time t_cam + t̂_d. A time-offset error δt = t_d − t̂_d shows as α·δt, α the
///    angular acceleration; the gyro bias b is removed per 5-s bin.
///  - ψ_vis: a rolling shutter exposes row ρ at (ρ + ½)·t_r after row 0, so the rate changes down the image by
///    ψ = α·t_r, α here the gyro through the images' slope (GyroSlope in the .cpp: a difference of the raw gyro carries
///    its vibration into the regressor, which scales t_r down). Nothing in a filter's state can produce it.
///  - ω_vis − ω̄_gyro, the gyro through the images' estimator: a relative focal error ε scales the images' rotational
///    flow but not the gyro's; its column is the response of ω_vis to ε through the whole fit.
/// Measured image velocities (not predicted ones) keep the filter's state out of it. Needs opt.camera and opt.imu.
/// Returns false, with the reason in `why`, when fewer than 50 images have 12+ features of known depth.
bool build_rate_design(const UsedData &data, const DiagnoseOptions &opt, const DiagnoseReport &rep, Design &dr,
                       std::string &why);

} // namespace ov_eval::diag
