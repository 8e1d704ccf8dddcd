#include "ov_msckf_ton/td/td_model.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/td/td_model_check.h"
#include "ov_msckf_ton/td/td_models.h"

namespace ovton::msckf {

namespace {

std::unique_ptr<TdModel> make_unchecked_model(const VioOptions &opt, std::function<double(int64_t)> truth) {
  const TimeOffsetOptions &o = opt.td;
  if (o.mode == TdMode::Oracle) {
    if (!truth)
      throw ovton::core::UsageError("td mode 'oracle' needs the dataset's td_truth/data.csv");
    return make_oracle_model(std::move(truth));
  }
  switch (resolve_td_process(o.mode, o.process)) {
  case TdProcess::Tpn:
    return make_tpn_model(o, opt.ton);
  case TdProcess::Drift:
    return make_drift_model(o);
  case TdProcess::RandomWalk:
    return make_random_walk_model(o.random_walk, o.adaptive_noise, o.adaptive_block_s);
  default: // a constant stays a constant (OpenVINS' model): adaptive noise would make it a random walk
    return make_random_walk_model(0.0, false);
  }
}

} // namespace

std::unique_ptr<TdModel> make_td_model(const VioOptions &opt, std::function<double(int64_t)> truth) {
  std::unique_ptr<TdModel> m = make_unchecked_model(opt, std::move(truth));
  const bool estimated = opt.td.mode != TdMode::Off && opt.td.mode != TdMode::Oracle;
  if (opt.td.model_check && estimated && m->kind() != TdProcess::Drift)
    return make_checked_model(std::move(m), opt.td);
  return m;
}

void propagate_td_covariance(State &s, double q_td, double q_rate, double dt_s) {
  if (s.estimates_td())
    propagate_offset_covariance(s, s.td_index, s.td_rate_index, q_td, q_rate, dt_s);
}

void propagate_offset_covariance(State &s, int d, int r, double q_td, double q_rate, double dt_s) {
  if (d < 0 || !(dt_s > 0))
    return;
  s.for_each_covariance([&](auto &P) {
    using T = covariance_scalar<decltype(P)>;
    if (r >= 0) {
      // Φ P Φᵀ with Φ = I + dt·e_d e_rᵀ: row d += dt·row r, then column d += dt·column r.
      P.row(d) += T(dt_s) * P.row(r);
      P.col(d) += T(dt_s) * P.col(r);
      const double qr = q_rate * q_rate;
      P(d, d) += T(qr * dt_s * dt_s * dt_s / 3.0);
      P(d, r) += T(qr * dt_s * dt_s / 2.0);
      P(r, d) += T(qr * dt_s * dt_s / 2.0);
      P(r, r) += T(qr * dt_s);
    }
    P(d, d) += T(q_td * q_td * dt_s);
  });
}

} // namespace ovton::msckf
