#pragma once
// Covariance matching for the time offset's process noise (Myers & Tapley 1976, scalar form): if the model is
// right, every t_d correction δ an update makes has E[δ²] = P⁻ − P⁺, where P⁻ already holds the process noise
// Q_used added since the previous image. Solving for Q gives one sample per image, Q̂ = δ² − (P⁻ − P⁺) + Q_used,
// summed over the image's updates; its running mean (per second) replaces q². A model whose prediction is off (TPN
// extrapolating a transient, a constant model on a drifting offset) makes corrections larger than its variance
// allows, Q̂ grows, σ(t_d) widens and the data get their weight back; a good prediction shrinks it to the floor.
// Block form (block_s > 0): a prediction that trails the offset makes many small corrections of one sign, each within
// its own image's variance, so per-image samples hardly see it (the trend adds (r·dt)² per image, r the rate error);
// their sum over the last block_s seconds does ((r·T)²). In a consistent filter the corrections are uncorrelated
// (white innovations), so E[(Σδ)²] = Σ(P⁻ − P⁺) still holds over a block and the sample Q̂ = (Σδ)² − Σ(P⁻ − P⁺) +
// ΣQ_used stays unbiased: the block changes what a sample can see, not what it expects. The block slides by one image
// (a Bartlett long-run variance), so the running mean still moves every image and averages overlapping blocks.
#include <algorithm>
#include <cmath>
#include <deque>

namespace ovton::msckf {

class TdNoiseAdapter {
public:
  /// q0: the configured noise [s/sqrt(s)] (start value and floor); block_s: the span over which corrections are
  /// summed into one sample (0: each image alone); window_s: time constant of the running mean.
  explicit TdNoiseAdapter(double q0, double block_s = 0.0, double window_s = 5.0, double q_max = 0.01)
      : floor_(q0 * q0), cap_(q_max * q_max), q2_(q0 * q0), mean_(q0 * q0), block_s_(block_s), window_s_(window_s) {}

  double q() const { return std::sqrt(q2_); }
  /// Process variance added during propagation since the last image.
  void add_process(double var) { q_used_ += var; }
  /// One EKF update's t_d mean and variance before and after.
  void add_update(double td_prior, double var_prior, double td_post, double var_post) {
    const double d = td_post - td_prior;
    sum_d_ += d;
    sum_d2_ += d * d;
    removed_ += var_prior - var_post;
  }
  /// Closes the image's sample over dt_s seconds since the previous image.
  void close_image(double dt_s) {
    if (dt_s > 0) {
      double per_s;
      if (block_s_ > 0) {
        block_.push_back({sum_d_, removed_, q_used_, dt_s});
        span_s_ += dt_s;
        while (span_s_ - block_.front().dt_s >= block_s_) {
          span_s_ -= block_.front().dt_s;
          block_.pop_front();
        }
        double d = 0, removed = 0, q_used = 0;
        for (const ImageSum &i : block_) {
          d += i.d;
          removed += i.removed;
          q_used += i.q_used;
        }
        per_s = (d * d - removed + q_used) / span_s_;
      } else {
        per_s = (sum_d2_ - removed_ + q_used_) / dt_s;
      }
      if (span_s_ >= block_s_) {
        const double a = std::min(1.0, dt_s / window_s_);
        // Blocks let their running mean go below the floor (not below 0: a block that holds the convergence from
        // the prior removes far more variance than its one squared sum shows, and would hold the mean down for
        // many windows): a mean held at the floor drifts upwards on the blocks' noisy samples (+33 % in q² on
        // white corrections, 3-s blocks). Per image it is held at the floor, as when that form was measured.
        mean_ = std::clamp((1 - a) * mean_ + a * per_s, 0.0, cap_);
        q2_ = std::clamp(mean_, floor_, cap_);
        if (!(block_s_ > 0))
          mean_ = q2_;
      }
    }
    sum_d_ = sum_d2_ = removed_ = q_used_ = 0.0;
  }

private:
  struct ImageSum {
    double d, removed, q_used, dt_s;
  };
  double floor_, cap_, q2_, mean_, block_s_, window_s_;
  double sum_d_ = 0.0, sum_d2_ = 0.0, removed_ = 0.0, q_used_ = 0.0, span_s_ = 0.0;
  std::deque<ImageSum> block_; ///< the last block_s seconds of images
};

} // namespace ovton::msckf
