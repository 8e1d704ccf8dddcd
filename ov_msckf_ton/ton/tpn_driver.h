#pragma once
// TPN inside the filter (paper Sec. IV-C, eq. 14, Algorithm 1 stages 3-4): after each image the filter's estimate
// t̂_d(K−1) is appended to the label buffer, the network is trained and predicts t_d^TPN(K); the propagation to the
// next image then drives the t_d mean at J_td = (t_d^TPN(K) − t̂_d(K−1)) / dt.
#include "ov_msckf_ton/ton/tpn.h"

namespace ovton::msckf {

class TpnDriver {
public:
  explicit TpnDriver(const TpnDriverOptions &options = {});

  /// Stages 3-4 after image K−1: pushes t̂_d(K−1) [s], trains and predicts t_d^TPN(K). Returns whether a prediction
  /// is available (enough labels).
  bool step(double td_estimate_s);
  bool has_prediction() const { return has_prediction_; }
  /// Forgets the labels (not the weights) and the prediction: the next labels do not continue the old sequence.
  void clear_labels() {
    tpn_.clear_labels();
    has_prediction_ = false;
  }
  /// t_d^TPN(K) [s]; only meaningful when has_prediction().
  double prediction() const { return prediction_; }

  /// Paper eq. 14 over `dt_s` seconds from the current mean `td_now_s`, clamped to ±td_rate_max; 0 without a
  /// prediction or for dt_s <= 0. `clamped`, when given, tells whether the bound was hit.
  double rate(double td_now_s, double dt_s, bool *clamped = nullptr) const;

  const ton::Tpn &network() const { return tpn_; }
  const TpnDriverOptions &options() const { return opt_; }

private:
  TpnDriverOptions opt_;
  ton::Tpn tpn_;
  double prediction_ = 0.0;
  bool has_prediction_ = false;
};

} // namespace ovton::msckf
