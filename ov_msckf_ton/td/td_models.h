#pragma once
// One factory per time-offset model (each defined in its own file of this folder); make_td_model() picks one.
#include "ov_msckf_ton/td/td_model.h"
#include "ov_msckf_ton/ton/tpn_driver.h"

#include <string>

namespace ovton::msckf {

/// t_d constant (q = 0: OpenVINS' model) or a random walk of q [s/sqrt(s)]; t_d at an image is the current mean.
/// adaptive: covariance matching (td_noise_adapter.h) over blocks of block_s seconds.
std::unique_ptr<TdModel> make_random_walk_model(double q, bool adaptive, double block_s = 0.0);

/// Beyond the paper: t_d and its rate ṫ_d in the state, the paper's eq. 4 (cumulative bias + noise) as a Kalman
/// process model: t_d' = t_d + ṫ_d·dt + w_td, ṫ_d' = ṫ_d + w_r.
std::unique_ptr<TdModel> make_drift_model(const TimeOffsetOptions &o);

/// The paper's TPN (Sec. IV-C, eq. 14, Algorithm 1 stages 3-4): the network's prediction drives the mean, t_d
/// carries random-walk noise.
std::unique_ptr<TdModel> make_tpn_model(const TimeOffsetOptions &o, const TonOptions &ton);
/// The TPN driver of a model made by make_tpn_model, nullptr for any other model.
const TpnDriver *tpn_driver_of(const TdModel &m);
/// The line a run's summary says TPN's start with ("" for a model that never ran TPN): from which image it had labels,
/// after which image it first predicted (until then t_d is a random walk), its trainings, restarts, and how often its
/// rate sat at the bound `rate_max_s_per_s` (time_offset.rate_max).
std::string describe_tpn_learning(const TdModelStats &st, double rate_max_s_per_s);

/// Mode oracle: t_d is the truth at every image (not estimated).
std::unique_ptr<TdModel> make_oracle_model(std::function<double(int64_t)> truth);

} // namespace ovton::msckf
