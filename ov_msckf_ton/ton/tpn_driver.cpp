#include "ov_msckf_ton/ton/tpn_driver.h"
#include "ov_core/types/errors.h"

#include <algorithm>
#include <cmath>

namespace ovton::msckf {

TpnDriver::TpnDriver(const TpnDriverOptions &options) : opt_(options), tpn_(options.tpn) {
  if (opt_.min_labels < 2)
    throw ovton::core::UsageError("TpnDriver: min_labels must be at least 2 (one input-target pair)");
  if (!(opt_.td_rate_max >= 0))
    throw ovton::core::UsageError("TpnDriver: td_rate_max must be >= 0");
}

bool TpnDriver::step(double td_estimate_s) {
  tpn_.push_estimate(td_estimate_s);
  has_prediction_ = false;
  if (tpn_.num_labels() < opt_.min_labels)
    return false;
  tpn_.train();
  prediction_ = tpn_.predict();
  has_prediction_ = std::isfinite(prediction_);
  return has_prediction_;
}

double TpnDriver::rate(double td_now_s, double dt_s, bool *clamped) const {
  if (clamped)
    *clamped = false;
  if (!has_prediction_ || !(dt_s > 0))
    return 0.0;
  const double j = (prediction_ - td_now_s) / dt_s;
  if (std::abs(j) <= opt_.td_rate_max)
    return j;
  if (clamped)
    *clamped = true;
  return std::clamp(j, -opt_.td_rate_max, opt_.td_rate_max);
}

} // namespace ovton::msckf
