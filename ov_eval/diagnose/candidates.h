#pragma once
// The candidate effects of `ovton diagnose`, as one table: key, model, the design columns it adds, the unit of each
// estimate, and whether it can be tested on rates. The designs (residual_design.h, rate_design.h) fill the columns,
// the stepwise selection (regression.h) tests them; docs/diagnose.md gives each model and its sign convention.
#include "ov_eval/diagnose.h"
#include "ov_eval/diagnose/regression.h"

#include <string>
#include <vector>

namespace ovton::eval::diag {

/// Time bins of the piecewise offset candidate (td_piecewise): a drift (kV, kVt) and, for the inner bins
/// b = 1 .. kTdBins − 2, their own offset beyond it (kTdBin0 + b − 1). The first and last bins carry none: with the
/// drift's two terms the offset per bin is free. So td_piecewise contains td_drift, which contains td_const.
constexpr int kTdBins = 8;

/// Columns of the design matrix; a candidate is a list of them, so nested candidates share columns. On the residual
/// design (pixels) they are as below; the rate design fills kV (α), kVt (α·(t − t_mid)), kVrow (α, on ψ rows), kFocal
/// (ω_vis's response to a unit focal error) and kGyroScale (−ω̄_gyro), whitened by each row's standard error.
enum Col : int {
  kV = 0,                  ///< image velocity [px/s]
  kVt,                     ///< image velocity × (t − t_mid) [px]
  kVrow,                   ///< image velocity × (row fraction − 0.5) [px/s]
  kFocal,                  ///< (fu·x, fv·y) [px]
  kPpU,                    ///< (1, 0)
  kPpV,                    ///< (0, 1)
  kRadial,                 ///< r²·(fu·x, fv·y) [px]
  kGyro0,                  ///< 9 columns B(x,y)·e_i·Θ_j [px·rad/rad]
  kGyroScale = kGyro0 + 9, ///< with the camera: −B(x,y)·R_CB·Θ [px], the nine above contracted with R_CB
  // Rates only (the rows ω_vis − ω̄_gyro, body frame): the gyro's linear errors and the camera-body rotation.
  kGyroAxY, ///< −e_y·ω̄_y: with kGyroScale, the y axis's own scale
  kGyroAxZ, ///< −e_z·ω̄_z
  kExtRot0, ///< 3 columns ω̄ × e_j: camera-body rotation error φ (R_BC true = Exp(φ)·R_BC)
  /// 3 columns −(e_i·e_jᵀ + e_j·e_iᵀ)·ω̄ for (i, j) = (x, y), (x, z), (y, z): the gyro's symmetric misalignment.
  kGyroMis0 = kExtRot0 + 3,
  /// Residual only: 3 columns −f·J_π(x)·e_c/z, a camera-body translation error seen in the camera frame.
  kExtTrans0 = kGyroMis0 + 3,
  /// α·1[time bin b] (rates) or V·1[bin b] (residual) for bins b = 1 .. kTdBins − 2; with kV and kVt, a piecewise
  /// offset.
  kTdBin0 = kExtTrans0 + 3,
  /// The accelerometer only (accel_design.h), as the gyro's scale: one scale for all axes (against gravity Σ_j A_j,
  /// on the filter's bias the specific force along the row's axis), and the y and z axes' own beyond it.
  kAccScale = kTdBin0 + kTdBins - 2,
  kAccAxY,
  kAccAxZ,
  kNumCols
};

/// The piecewise offset's bin of a row at t seconds into a log of `duration_s`.
inline int td_bin(double t, double duration_s) {
  const int b = static_cast<int>(kTdBins * t / (duration_s > 0 ? duration_s : 1.0));
  return b < 0 ? 0 : b >= kTdBins ? kTdBins - 1 : b;
}

/// A candidate's coefficients in the fit that estimated them (at: their positions in fit.beta, in column order).
struct Coefs {
  const Fit &fit;
  std::vector<int> at;
  double b(int i) const { return fit.beta(at[i]); }
  double s(int i) const;
  double cov(int i, int j) const { return fit.cov(at[i], at[j]); }
};

/// The estimates shown for a candidate, in the user's units, from its coefficients.
using EstimatesFn = std::vector<EffectEstimate> (*)(const Coefs &c, const DiagnoseReport &rep, const Design &d);

/// What a candidate needs of the residual log's rows to be tested on the residual (the rate design has both); Rates:
/// it has no model on the residual and is tested on rates only (--dataset); AccelBias: tested on the filter's
/// accelerometer bias only (the calibration log and --dataset, accel_design.h).
enum class Needs { Nothing, Velocity, BodyRates, Rates, AccelBias };

struct CandidateDef {
  std::string key;              ///< td_const, td_drift, rolling_shutter, focal, principal_point, radial_k1, gyro_scale
  std::vector<int> cols;        ///< its columns
  std::vector<int> camera_cols; ///< its columns when the dataset's camera is known, if different
  Needs needs = Needs::Nothing;
  EstimatesFn estimates = nullptr;
  std::string description;      ///< the model on the residual, in one line
  std::string rate_description; ///< the model on rates; empty: tested on the residual only
  std::string fallback_note;    ///< rate-capable candidates: what a test on the residual is worth
  std::string xlabel;           ///< the plot's x axis on the residual
  std::string rate_xlabel;      ///< the plot's x axis on rates
  /// The largest error a rig's calibration is plausibly off by, in the unit of its first estimate: three times the
  /// prior σ of the filter's matching calibration option (ov_msckf_ton/core/vio_options.h). A log whose smallest
  /// nameable size (the bar against F with its independent clusters, times the estimate's SE) is larger cannot tell
  /// a calibrated rig from a miscalibrated one: not testable on it. 0: no such size.
  double testable_size = 0;

  bool rate_capable() const { return !rate_description.empty(); }
  const std::vector<int> &columns(bool have_camera) const {
    return have_camera && !camera_cols.empty() ? camera_cols : cols;
  }
};

/// Every candidate, in the order ties are ranked in.
const std::vector<CandidateDef> &candidate_table();

/// The candidate's estimates from `fit` over the columns `joint` (its own columns `cols` among them).
std::vector<EffectEstimate> candidate_estimates(const CandidateDef &def, const std::vector<int> &cols, const Fit &fit,
                                                const std::vector<int> &joint, const DiagnoseReport &rep,
                                                const Design &d);

} // namespace ovton::eval::diag
