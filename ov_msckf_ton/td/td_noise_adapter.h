#pragma once
// Covariance matching for the time offset's process noise (Myers & Tapley 1976, scalar form): if the model is
// right, every t_d correction δ an update makes has E[δ²] = P⁻ − P⁺, where P⁻ already holds the process noise
// Q_used added since the previous image. Solving for Q gives one sample per image, Q̂ = δ² − (P⁻ − P⁺) + Q_used,
// summed over the image's updates; its running mean (per second) replaces q². A model whose prediction is off (TPN
// extrapolating a transient, a constant model on a drifting offset) makes corrections larger than its variance
// allows, Q̂ grows, σ(t_d) widens and the data get their weight back; a good prediction shrinks it to the floor.
#include <algorithm>
#include <cmath>

namespace ov_msckf_ton {

class TdNoiseAdapter {
public:
  /// q0: the configured noise [s/sqrt(s)] (start value and floor); window_s: time constant of the running mean.
  TdNoiseAdapter(double q0, double window_s = 5.0, double q_max = 0.01)
      : floor_(q0 * q0), cap_(q_max * q_max), q2_(q0 * q0), window_s_(window_s) {}

  double q() const { return std::sqrt(q2_); }
  /// Process variance added during propagation since the last image.
  void add_process(double var) { q_used_ += var; }
  /// One EKF update's t_d mean and variance before and after.
  void add_update(double td_prior, double var_prior, double td_post, double var_post) {
    const double d = td_post - td_prior;
    sample_ += d * d - (var_prior - var_post);
  }
  /// Closes the image's sample over dt_s seconds since the previous image.
  void close_image(double dt_s) {
    if (dt_s > 0) {
      const double per_s = (sample_ + q_used_) / dt_s;
      const double a = std::min(1.0, dt_s / window_s_);
      q2_ = std::clamp((1 - a) * q2_ + a * per_s, floor_, cap_);
    }
    sample_ = 0.0;
    q_used_ = 0.0;
  }

private:
  double floor_, cap_, q2_, window_s_;
  double sample_ = 0.0, q_used_ = 0.0;
};

} // namespace ov_msckf_ton
