#include "ov_eval/diagnose/candidates.h"

#include <algorithm>
#include <cmath>

namespace ov_eval::diag {

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

std::vector<int> gyro_columns() {
  std::vector<int> gyro;
  for (int i = 0; i < 9; ++i)
    gyro.push_back(kGyro0 + i);
  return gyro;
}

const char *const kOffsetFallback = "a lower bound, the poses absorb most of an offset";
const char *const kAbsorbedFallback = "a lower bound, the poses absorb most of it";

} // namespace

const std::vector<CandidateDef> &candidate_table() {
  // One candidate per entry: key, columns, columns with the camera, needs, estimates; its models on the residual and
  // on rates, what the residual is worth for a rate-capable one; the plots' x axes on the residual and on rates.
  // clang-format off
  static const std::vector<CandidateDef> table = {
      {"td_const", {kV}, {}, Needs::Velocity, td_const,
       "constant time-offset error: r = V·δt",
       "constant time-offset error, from rates: ω_vis − ω_gyro = α·δt − b",
       kOffsetFallback,
       "image velocity V [px/s]",
       "angular acceleration alpha, bias removed, / SE [1/s]"},
      {"td_drift", {kV, kVt}, {}, Needs::Velocity, td_drift,
       "drifting time-offset error: r = V·(δt + ḋ·(t − t_mid))",
       "drifting time-offset error, from rates: ω_vis − ω_gyro = α·(δt + ḋ·(t − t_mid)) − b",
       kOffsetFallback,
       "fitted td_drift effect [px]",
       "fitted alpha * dt(t), bias removed, / SE"},
      {"rolling_shutter", {kVrow}, {}, Needs::Velocity, readout,
       "rolling-shutter readout: r = V·(row/height − 0.5)·t_r",
       "rolling-shutter readout, from rates: ψ_vis = α·t_r (rate change from top row to bottom)",
       kAbsorbedFallback,
       "V * (row fraction - 0.5) [px/s]",
       "angular acceleration alpha / SE of psi_vis [1/s]"},
      {"focal", {kFocal}, {}, Needs::Nothing, focal,
       "focal-length error: r = ε·(fu·x, fv·y), δf = ε·f",
       "focal-length error, from rates: ω_vis − ω̄_gyro = ε·∂ω_vis/∂ε (the whole rate fit's response) − b",
       kAbsorbedFallback,
       "image position from the centre (f * x), point-absorbed part removed [px]",
       "response of w_vis to a unit focal error, bias removed, / SE"},
      {"principal_point", {kPpU, kPpV}, {}, Needs::Nothing, principal_point,
       "principal-point error: r = (δcu, δcv)",
       "", "",
       "fitted principal_point effect [px]",
       ""},
      {"radial_k1", {kRadial}, {}, Needs::Nothing, radial_k1,
       "radial distortion error: r = δk1·|xy|²·(fu·x, fv·y)",
       "", "",
       "|x|^2 * f * x, point-absorbed part removed [px]",
       ""},
      // With the camera, R_CB is known and the gyro scale is one number: on rates −ω̄_gyro, on the residual −B·R_CB·Θ.
      {"gyro_scale", gyro_columns(), {kGyroScale}, Needs::BodyRates, gyro_scale,
       "gyro scale error: r = −s·B(x,y)·R_CB·∫ω dt over the track",
       "gyro scale error, from rates: ω_vis − ω̄_gyro = −s·ω̄_gyro − b",
       kAbsorbedFallback,
       "fitted gyro_scale effect [px]",
       "-w_gyro through the images' estimator, bias removed, / SE [rad/s]"},
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

} // namespace ov_eval::diag
