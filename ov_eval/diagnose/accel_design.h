#pragma once
// The design on the filter's accelerometer bias (docs/diagnose.md, "Accelerometer scale"): an accelerometer scale
// error is in no image, and the filter's poses follow the images; what the filter does with it is to move its
// accelerometer bias. It reads a = a_m − b̂_a while the truth is a = a_m/(1 + s) (per axis), so its bias follows
// b̂_a,j ≈ s_j·f_j + c_j, f the specific force the accelerometer measures along body axis j.
#include "ov_eval/diagnose/regression.h"
#include "ov_eval/diagnose/tracks.h"

namespace ovton::eval::diag {

/// Three rows per update of the calibration log (one per body axis): the filter's b̂_a,j against the measured specific
/// force f_j (the raw accelerometer through the filter's D_a, low-passed like the bias follows it), both with their
/// means per bias bin removed (the bias's own random walk), clustered per second. Needs opt.calibration (50+ updates
/// in the used span) and opt.imu; false otherwise, with the reason in `why`. Also false when the filter estimated the
/// accelerometer's intrinsics (D_a varies over the log): its bias then trades against its own D_a as that converges,
/// so the bias no longer follows a scale error alone (on the gyro-scale flight with `imu_intrinsics` on, seeds 1-4 and
/// 7, the regression read 2-8 % on a perfect accelerometer at up to 11σ: docs/diagnose.md); the filter's D_a and its
/// σ are the answer there.
/// With the IMU state in the calibration log (has_state on every row), the design is build_accel_gravity_design's
/// instead.
bool build_accel_design(const UsedData &data, const DiagnoseOptions &opt, const DiagnoseReport &rep, Design &db,
                        std::string &why);

/// The accelerometer against gravity (docs/diagnose.md, "Accelerometer scale against gravity"): over windows of 0.5 s
/// between the filter's states, Δv = Σ_j κ_j·∫R·e_j·a_j dt − ∫R dt·b + g·T with κ_j = 1/(1 + s_j). The images fix
/// the trajectory's shape but not its size, so the estimate's own scale μ is free (Δv/μ); gravity, a known
/// acceleration turned in the body frame by the attitude, fixes κ. Three rows per window (world axes): the data
/// Σ_j A_j + g·T − Δv, the candidate's columns A_j (coefficients β_j = 1 − κ_j), a body-frame bias per 5-s bin and
/// Δv (μ) projected out. Needs the IMU state on every calibration-log row (`ovton run` writes it since session 35),
/// opt.imu, 10 windows; the filter's D_a and D_w at each reading are applied (an estimated D_a is then read as no
/// error).
bool build_accel_gravity_design(const UsedData &data, const DiagnoseOptions &opt, const DiagnoseReport &rep, Design &db,
                                std::string &why);

} // namespace ovton::eval::diag
