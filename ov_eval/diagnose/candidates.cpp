#include "ov_eval/diagnose/candidates.h"

#include <algorithm>
#include <cmath>

namespace ovton::eval::diag {

double Coefs::s(int i) const {
  return std::sqrt(std::max(0.0, fit.cov(at[i], at[i])));
}

namespace {

std::vector<EffectEstimate> td_const(const Coefs &c, const DiagnoseReport &, const Design &) {
  return {{"offset error δt", "ms", 1e3 * c.b(0), 1e3 * c.s(0)}};
}

std::vector<EffectEstimate> td_drift(const Coefs &c, const DiagnoseReport &, const Design &d) {
  const double t0 = -d.t_mid; // start of the log relative to the centre
  const double v = c.cov(0, 0) + t0 * t0 * c.cov(1, 1) + 2 * t0 * c.cov(0, 1);
  return {{"drift rate", "ms/s", 1e3 * c.b(1), 1e3 * c.s(1)},
          {"offset error at start", "ms", 1e3 * (c.b(0) + t0 * c.b(1)), 1e3 * std::sqrt(std::max(0.0, v))},
          {"offset error at mid-log", "ms", 1e3 * c.b(0), 1e3 * c.s(0)}};
}

std::vector<EffectEstimate> readout(const Coefs &c, const DiagnoseReport &, const Design &) {
  return {{"readout time t_r", "ms", 1e3 * c.b(0), 1e3 * c.s(0)}};
}

std::vector<EffectEstimate> focal(const Coefs &c, const DiagnoseReport &rep, const Design &) {
  const double f = 0.5 * (rep.fu + rep.fv);
  return {{"focal error δf", "px", f * c.b(0), f * c.s(0)},
          {"relative focal error ε", "%", 100 * c.b(0), 100 * c.s(0)}};
}

std::vector<EffectEstimate> principal_point(const Coefs &c, const DiagnoseReport &, const Design &) {
  return {{"δcu", "px", c.b(0), c.s(0)}, {"δcv", "px", c.b(1), c.s(1)}};
}

std::vector<EffectEstimate> radial_k1(const Coefs &c, const DiagnoseReport &, const Design &) {
  return {{"δk1", "", c.b(0), c.s(0)}};
}

std::vector<EffectEstimate> gyro_scale(const Coefs &c, const DiagnoseReport &, const Design &) {
  if (c.at.size() == 1) // R_CB known: the column is −ω̄_gyro or −B·R_CB·Θ
    return {{"gyro scale error s", "%", 100 * c.b(0), 100 * c.s(0)}};
  // M = −s·R_CB: |M|_F = √3·|s| and det M = −s³, so s = −sign(det M)·|M|_F/√3 (delta-method σ).
  Eigen::Matrix3d M;
  Eigen::Matrix<double, 9, 9> C;
  for (int i = 0; i < 9; ++i) {
    M(i / 3, i % 3) = c.b(i);
    for (int j = 0; j < 9; ++j)
      C(i, j) = c.cov(i, j);
  }
  const double nrm = M.norm();
  const double sgn = M.determinant() > 0 ? -1.0 : 1.0;
  Eigen::Matrix<double, 9, 1> g;
  for (int i = 0; i < 9; ++i)
    g(i) = nrm > 0 ? sgn * M(i / 3, i % 3) / (nrm * std::sqrt(3.0)) : 0.0;
  return {{"gyro scale error s", "%", 100 * sgn * nrm / std::sqrt(3.0),
           100 * std::sqrt(std::max(0.0, double(g.transpose() * C * g)))}};
}

/// Per-axis gyro scale: kGyroScale's coefficient is s_x, kGyroAxY's and kGyroAxZ's add to it for s_y and s_z.
std::vector<EffectEstimate> gyro_axes(const Coefs &c, const DiagnoseReport &, const Design &) {
  std::vector<EffectEstimate> out;
  const char *names[3] = {"gyro scale error s_x", "gyro scale error s_y", "gyro scale error s_z"};
  for (int a = 0; a < 3; ++a) {
    const double v = a == 0 ? c.b(0) : c.b(0) + c.b(a);
    const double var = a == 0 ? c.cov(0, 0) : c.cov(0, 0) + c.cov(a, a) + 2 * c.cov(0, a);
    out.push_back({names[a], "%", 100 * v, 100 * std::sqrt(std::max(0.0, var))});
  }
  return out;
}

/// The accelerometer's scale from a coefficient of its columns: against gravity β = 1 − 1/(1 + s), so s = β/(1 − β)
/// with the delta-method σ; on the filter's bias (which follows s·f) β is s (accel_design.h).
EffectEstimate accel_scale_from(double beta, double se, const std::string &name, const Design &d) {
  const double k = d.accel_against_gravity ? 1.0 - beta : 1.0;
  return {name, "%", 100 * beta / k, 100 * se / (k * k)};
}

std::vector<EffectEstimate> accel_scale(const Coefs &c, const DiagnoseReport &, const Design &d) {
  return {accel_scale_from(c.b(0), c.s(0), "accel scale error s", d)};
}

/// Per-axis accelerometer scale: kAccScale's coefficient is the x axis's, kAccAxY's and kAccAxZ's add to it.
std::vector<EffectEstimate> accel_axes(const Coefs &c, const DiagnoseReport &, const Design &d) {
  std::vector<EffectEstimate> out;
  const char *names[3] = {"accel scale error s_x", "accel scale error s_y", "accel scale error s_z"};
  for (int a = 0; a < 3; ++a) {
    const double v = a == 0 ? c.b(0) : c.b(0) + c.b(a);
    const double var = a == 0 ? c.cov(0, 0) : c.cov(0, 0) + c.cov(a, a) + 2 * c.cov(0, a);
    out.push_back(accel_scale_from(v, std::sqrt(std::max(0.0, var)), names[a], d));
  }
  return out;
}

/// The size of a vector estimate (first three coefficients) and its delta-method SE, scaled to `unit_per`.
EffectEstimate vector_norm(const Coefs &c, const std::string &name, const std::string &unit, double unit_per) {
  const Eigen::Vector3d v(c.b(0), c.b(1), c.b(2));
  Eigen::Matrix3d C;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      C(i, j) = c.cov(i, j);
  const double n = v.norm();
  const Eigen::Vector3d g = n > 0 ? (v / n).eval() : Eigen::Vector3d::Zero();
  return {name, unit, unit_per * n, unit_per * std::sqrt(std::max(0.0, double(g.transpose() * C * g)))};
}

std::vector<EffectEstimate> extrinsic_rotation(const Coefs &c, const DiagnoseReport &, const Design &) {
  const double deg = 180.0 / M_PI;
  return {vector_norm(c, "rotation error |φ|", "deg", deg),
          {"φ_x (body)", "deg", deg * c.b(0), deg * c.s(0)},
          {"φ_y (body)", "deg", deg * c.b(1), deg * c.s(1)},
          {"φ_z (body)", "deg", deg * c.b(2), deg * c.s(2)}};
}

/// The gyro's symmetric misalignment, M_xy, M_xz, M_yz, in mrad.
std::vector<EffectEstimate> gyro_misalignment(const Coefs &c, const DiagnoseReport &, const Design &) {
  return {vector_norm(c, "gyro misalignment |m|", "mrad", 1e3),
          {"gyro misalignment m_xy", "mrad", 1e3 * c.b(0), 1e3 * c.s(0)},
          {"gyro misalignment m_xz", "mrad", 1e3 * c.b(1), 1e3 * c.s(1)},
          {"gyro misalignment m_yz", "mrad", 1e3 * c.b(2), 1e3 * c.s(2)}};
}

/// Fitted in the camera frame; with the dataset's camera also shown in the body frame (δp_B = R_BC·δp_C).
std::vector<EffectEstimate> extrinsic_translation(const Coefs &c, const DiagnoseReport &rep, const Design &) {
  std::vector<EffectEstimate> out = {vector_norm(c, "translation error |δp|", "mm", 1e3)};
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  const bool body = rep.options.have_camera;
  if (body)
    R = rep.options.camera.T_BC.block<3, 3>(0, 0);
  Eigen::Matrix3d C;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      C(i, j) = c.cov(i, j);
  const Eigen::Vector3d v = R * Eigen::Vector3d(c.b(0), c.b(1), c.b(2));
  const Eigen::Matrix3d Cv = R * C * R.transpose();
  const char *axes[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a)
    out.push_back({std::string("δp_") + axes[a] + (body ? " (body)" : " (camera)"), "mm", 1e3 * v(a),
                   1e3 * std::sqrt(std::max(0.0, Cv(a, a)))});
  return out;
}

/// Per-bin offsets at the bins' centres, δ_b = β_V + β_Vt·(t_b − t_mid) (+ β_b for the inner bins): their mean,
/// their spread about it (RMS, the size of a wander) and their range; delta-method SEs.
std::vector<EffectEstimate> td_piecewise(const Coefs &c, const DiagnoseReport &, const Design &d) {
  const int K = kTdBins, p = kTdBins; // kV, kVt and K − 2 inner bins
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(K, p), C(p, p);
  Eigen::VectorXd beta(p);
  for (int k = 0; k < K; ++k) {
    T(k, 0) = 1.0;
    T(k, 1) = (k + 0.5) * 2 * d.t_mid / K - d.t_mid;
    if (k > 0 && k < K - 1)
      T(k, k + 1) = 1.0;
  }
  for (int i = 0; i < p; ++i) {
    beta(i) = c.b(i);
    for (int j = 0; j < p; ++j)
      C(i, j) = c.cov(i, j);
  }
  const Eigen::VectorXd delta = T * beta;
  const Eigen::MatrixXd Cd = T * C * T.transpose();
  const double mean = delta.mean();
  const Eigen::VectorXd dev = delta.array() - mean;
  const double rms = std::sqrt(dev.squaredNorm() / K);
  const Eigen::VectorXd g_rms = rms > 0 ? (dev / (K * rms)).eval() : Eigen::VectorXd::Zero(K);
  const Eigen::VectorXd g_mean = Eigen::VectorXd::Constant(K, 1.0 / K);
  Eigen::Index lo = 0, hi = 0;
  delta.minCoeff(&lo);
  delta.maxCoeff(&hi);
  const double var_range = Cd(hi, hi) + Cd(lo, lo) - 2 * Cd(hi, lo);
  const auto se = [&](const Eigen::VectorXd &g) { return 1e3 * std::sqrt(std::max(0.0, double(g.dot(Cd * g)))); };
  return {{"offset error spread (RMS over bins)", "ms", 1e3 * rms, se(g_rms)},
          {"offset error, mean over bins", "ms", 1e3 * mean, se(g_mean)},
          {"offset error range (max − min bin)", "ms", 1e3 * (delta(hi) - delta(lo)),
           1e3 * std::sqrt(std::max(0.0, var_range))}};
}

std::vector<int> span(int first, int count, std::vector<int> head = {}) {
  for (int i = 0; i < count; ++i)
    head.push_back(first + i);
  return head;
}

std::vector<int> gyro_columns() {
  std::vector<int> gyro;
  for (int i = 0; i < 9; ++i)
    gyro.push_back(kGyro0 + i);
  return gyro;
}

// Prior σ of the filter's calibration options (ov_msckf_ton/core/vio_options.h: TdOptions, CalibrationOptions), in
// the units of each candidate's first estimate: the testable sizes are three of them (CandidateDef::testable_size).
constexpr double kTdPriorMs = 10.0, kTdRatePriorMsPerS = 1.0, kReadoutPriorMs = 10.0, kFocalPriorPx = 2.0,
                 kCenterPriorPx = 2.0, kDistortionPrior = 0.005, kImuPriorPct = 1.0, kImuPriorMrad = 10.0,
                 kExtRotPriorDeg = 0.01 * 180.0 / M_PI, kExtPosPriorMm = 10.0;

const char *const kOffsetFallback = "a lower bound, the poses absorb most of an offset";
const char *const kAbsorbedFallback = "a lower bound, the poses absorb most of it";

} // namespace

const std::vector<CandidateDef> &candidate_table() {
  // One candidate per entry: key, columns, columns with the camera, needs, estimates; its models on the residual and
  // on rates, what the residual is worth for a rate-capable one; the plots' x axes on the residual and on rates; the
  // size it must resolve to be testable.
  // clang-format off
  static const std::vector<CandidateDef> table = {
      {"td_const", {kV}, {}, Needs::Velocity, td_const,
       "constant time-offset error: r = V·δt",
       "constant time-offset error, from rates: ω_vis − ω_gyro = α·δt − b",
       kOffsetFallback,
       "image velocity V [px/s]",
       "angular acceleration alpha, bias removed, / SE [1/s]", 3 * kTdPriorMs},
      {"td_drift", {kV, kVt}, {}, Needs::Velocity, td_drift,
       "drifting time-offset error: r = V·(δt + ḋ·(t − t_mid))",
       "drifting time-offset error, from rates: ω_vis − ω_gyro = α·(δt + ḋ·(t − t_mid)) − b",
       kOffsetFallback,
       "fitted td_drift effect [px]",
       "fitted alpha * dt(t), bias removed, / SE", 3 * kTdRatePriorMsPerS},
      {"rolling_shutter", {kVrow}, {}, Needs::Velocity, readout,
       "rolling-shutter readout: r = V·(row/height − 0.5)·t_r",
       "rolling-shutter readout, from rates: ψ_vis = α·t_r (rate change from top row to bottom)",
       kAbsorbedFallback,
       "V * (row fraction - 0.5) [px/s]",
       "angular acceleration alpha / SE of psi_vis [1/s]", 3 * kReadoutPriorMs},
      {"focal", {kFocal}, {}, Needs::Nothing, focal,
       "focal-length error: r = ε·(fu·x, fv·y), δf = ε·f",
       "focal-length error, from rates: ω_vis − ω̄_gyro = ε·∂ω_vis/∂ε (the whole rate fit's response) − b",
       kAbsorbedFallback,
       "image position from the centre (f * x), point-absorbed part removed [px]",
       "response of w_vis to a unit focal error, bias removed, / SE", 3 * kFocalPriorPx},
      {"principal_point", {kPpU, kPpV}, {}, Needs::Nothing, principal_point,
       "principal-point error: r = (δcu, δcv)",
       "", "",
       "fitted principal_point effect [px]",
       "", 3 * kCenterPriorPx},
      {"radial_k1", {kRadial}, {}, Needs::Nothing, radial_k1,
       "radial distortion error: r = δk1·|xy|²·(fu·x, fv·y)",
       "", "",
       "|x|^2 * f * x, point-absorbed part removed [px]",
       "", 3 * kDistortionPrior},
      // With the camera, R_CB is known and the gyro scale is one number: on rates −ω̄_gyro, on the residual −B·R_CB·Θ.
      {"gyro_scale", gyro_columns(), {kGyroScale}, Needs::BodyRates, gyro_scale,
       "gyro scale error: r = −s·B(x,y)·R_CB·∫ω dt over the track",
       "gyro scale error, from rates: ω_vis − ω̄_gyro = −s·ω̄_gyro − b",
       kAbsorbedFallback,
       "fitted gyro_scale effect [px]",
       "-w_gyro through the images' estimator, bias removed, / SE [rad/s]", 3 * kImuPriorPct},
      // Contains gyro_scale: selected only when the axes differ beyond one common scale.
      {"gyro_scale_axes", {kGyroScale, kGyroAxY, kGyroAxZ}, {}, Needs::Rates, gyro_axes,
       "per-axis gyro scale error (rates only)",
       "per-axis gyro scale error, from rates: ω_vis − ω̄_gyro = −diag(s)·ω̄_gyro − b (body axes)",
       "", "", "fitted gyro_scale_axes effect, / SE", 3 * kImuPriorPct},
      // The antisymmetric part of the gyro's linear error: on rates a camera-body rotation and a gyro axis rotation
      // are the same thing (only the accelerometer could tell them apart); it is named as the extrinsic.
      {"extrinsic_rotation", span(kExtRot0, 3), {}, Needs::Rates, extrinsic_rotation,
       "camera-IMU rotation error (rates only)",
       "camera-IMU rotation error, from rates: ω_vis − ω̄_gyro = ω̄_gyro × φ − b (R_BC true = Exp(φ)·R_BC)",
       "", "", "fitted extrinsic_rotation effect, / SE", 3 * kExtRotPriorDeg},
      // The symmetric part of the gyro's off-diagonal errors (axes not orthogonal): unlike the antisymmetric part it
      // cannot be a camera-body rotation.
      {"gyro_misalignment", span(kGyroMis0, 3), {}, Needs::Rates, gyro_misalignment,
       "gyro axis misalignment (rates only)",
       "gyro axis misalignment, from rates: ω_vis − ω̄_gyro = −M·ω̄_gyro − b, M symmetric with a zero diagonal",
       "", "", "fitted gyro_misalignment effect, / SE", 3 * kImuPriorMrad},
      // The accelerometer's scale: no image shows it. Against gravity through the filter's attitude and velocity
      // when the calibration log carries them; otherwise the filter's accelerometer bias follows it (accel_design.h).
      {"accel_scale", {kAccScale}, {}, Needs::AccelBias, accel_scale,
       "accelerometer scale error (needs the calibration log and --dataset): against gravity, Δv = ∫R·a dt/(1 + s) − "
       "∫R dt·b + g·T over 0.5-s windows of the filter's states, the trajectory's own scale free; from logs without "
       "the IMU state, the filter's accelerometer bias b̂_a,j = s·f_j + c_j",
       "", "", "specific force along the row's axis, bin means removed [m/s^2]", "", 3 * kImuPriorPct},
      // Contains accel_scale: selected only when the axes differ beyond one common scale.
      {"accel_scale_axes", {kAccScale, kAccAxY, kAccAxZ}, {}, Needs::AccelBias, accel_axes,
       "per-axis accelerometer scale error (body axes), as accel_scale with s_j per axis",
       "", "", "fitted accel_scale_axes effect", "", 3 * kImuPriorPct},
      {"extrinsic_translation", span(kExtTrans0, 3), {}, Needs::Nothing, extrinsic_translation,
       "camera-IMU translation error: r = −f·J_π(x)·δp_C/z (what the rotation along a track leaves of it)",
       "", "",
       "fitted extrinsic_translation effect [px]",
       "", 3 * kExtPosPriorMm},
      // Contains td_drift (and td_const): selected only when the offset varies beyond one slope. Against td_const
      // its added columns test whether the offset varies at all over the log. As a sibling of the drift (8 bins, no
      // slope) it took the drift's place on a pure 1 ms/s drift: the bins also fit the rates' per-bin floor.
      {"td_piecewise", span(kTdBin0, kTdBins - 2, {kV, kVt}), {}, Needs::Velocity, td_piecewise,
       "time-offset error of any shape: r = V·(δt + ḋ·(t − t_mid) + δt_b), δt_b per inner time bin",
       "time-offset error of any shape, from rates: ω_vis − ω_gyro = α·(δt + ḋ·(t − t_mid) + δt_b) − b, δt_b per inner "
       "time bin",
       kOffsetFallback,
       "fitted td_piecewise effect [px]",
       "fitted alpha * dt_b, bias removed, / SE", 3 * kTdPriorMs},
  };
  // clang-format on
  return table;
}

std::vector<EffectEstimate> candidate_estimates(const CandidateDef &def, const std::vector<int> &cols, const Fit &fit,
                                                const std::vector<int> &joint, const DiagnoseReport &rep,
                                                const Design &d) {
  Coefs c{fit, {}};
  for (int col : cols)
    c.at.push_back(static_cast<int>(std::find(joint.begin(), joint.end(), col) - joint.begin()));
  return def.estimates(c, rep, d);
}

} // namespace ovton::eval::diag
