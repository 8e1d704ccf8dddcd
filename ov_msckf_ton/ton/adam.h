#pragma once
// Adam (Kingma & Ba 2015) over a fixed-size flat parameter vector, with PyTorch's default betas and epsilon.
#include "ov_msckf_ton/ton/ton_error.h"

#include <Eigen/Core>
#include <cmath>

namespace ovton::msckf {
namespace ton {

template <int N> class Adam {
public:
  using Vec = Eigen::Matrix<double, N, 1>;

  explicit Adam(double learning_rate = 1e-3, double beta1 = 0.9, double beta2 = 0.999, double eps = 1e-8)
      : lr_(learning_rate), beta1_(beta1), beta2_(beta2), eps_(eps) {
    OVTON_TON_CHECK(learning_rate > 0.0, "Adam: learning rate must be positive");
    OVTON_TON_CHECK(beta1 >= 0.0 && beta1 < 1.0 && beta2 >= 0.0 && beta2 < 1.0, "Adam: betas must be in [0,1)");
    reset();
  }

  /// Forget the moment estimates (e.g. when the network is re-initialised).
  void reset() {
    m_.setZero();
    v_.setZero();
    t_ = 0;
  }

  void set_learning_rate(double lr) {
    OVTON_TON_CHECK(lr > 0.0, "Adam: learning rate must be positive");
    lr_ = lr;
  }
  double learning_rate() const { return lr_; }
  long steps() const { return t_; }

  void step(Vec &params, const Vec &grad) {
    ++t_;
    m_ = beta1_ * m_ + (1.0 - beta1_) * grad;
    v_ = beta2_ * v_ + (1.0 - beta2_) * grad.cwiseAbs2();
    // Bias-corrected moments, written as PyTorch does so that the same lr behaves the same as in the paper.
    const double bc1 = 1.0 - std::pow(beta1_, static_cast<double>(t_));
    const double bc2 = 1.0 - std::pow(beta2_, static_cast<double>(t_));
    const double step = lr_ / bc1;
    params.array() -= step * m_.array() / ((v_.array() / bc2).sqrt() + eps_);
  }

private:
  double lr_, beta1_, beta2_, eps_;
  Vec m_, v_;
  long t_ = 0;
};

} // namespace ton
} // namespace ovton::msckf
