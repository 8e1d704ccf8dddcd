#pragma once
// Two-hidden-layer perceptron with a linear output, trained by hand-written backpropagation.
//
//   z1 = W1 x + b1,  a1 = tanh(z1)
//   z2 = W2 a1 + b2, a2 = tanh(z2)
//   y  = W3 a2 + b3
// Loss (paper eq. 7): L = 1/n sum ||y - y*||^2.
//
// tanh rather than ReLU: with 5 units per layer a dead ReLU unit removes a fifth of the layer for good, and the
// online warm start would carry it from frame to frame; tanh is smooth, so the finite-difference gradient test is
// exact to rounding instead of failing whenever a pre-activation sits near a kink; and the inputs are min-max
// normalised to [0,1], so the net is too shallow for tanh saturation to matter.
#include "ov_msckf_ton/ton/random_init.h"
#include "ov_msckf_ton/ton/sequence_set.h"
#include "ov_msckf_ton/ton/ton_error.h"

#include <Eigen/Core>
#include <cmath>
#include <random>
#include <type_traits>

namespace ovton::msckf {
namespace ton {

template <int In, int H1, int H2, int Out> class Mlp {
public:
  static constexpr int kOffW1 = 0;
  static constexpr int kOffB1 = kOffW1 + H1 * In;
  static constexpr int kOffW2 = kOffB1 + H1;
  static constexpr int kOffB2 = kOffW2 + H2 * H1;
  static constexpr int kOffW3 = kOffB2 + H2;
  static constexpr int kOffB3 = kOffW3 + Out * H2;
  static constexpr int kNumParams = kOffB3 + Out;

  using Params = Eigen::Matrix<double, kNumParams, 1>;
  using Input = Eigen::Matrix<double, In, 1>;
  using Output = Eigen::Matrix<double, Out, 1>;
  using Data = PairSet<In, Out>;

  Mlp() : params_(Params::Zero()) {}

  /// PyTorch's nn.Linear default: weights and biases U(-1/sqrt(fan_in), 1/sqrt(fan_in)).
  void init(std::mt19937 &rng) {
    fill_uniform(block<H1, In>(params_, kOffW1), rng, 1.0 / std::sqrt(double(In)));
    fill_uniform(block<H1, 1>(params_, kOffB1), rng, 1.0 / std::sqrt(double(In)));
    fill_uniform(block<H2, H1>(params_, kOffW2), rng, 1.0 / std::sqrt(double(H1)));
    fill_uniform(block<H2, 1>(params_, kOffB2), rng, 1.0 / std::sqrt(double(H1)));
    fill_uniform(block<Out, H2>(params_, kOffW3), rng, 1.0 / std::sqrt(double(H2)));
    fill_uniform(block<Out, 1>(params_, kOffB3), rng, 1.0 / std::sqrt(double(H2)));
  }

  const Params &params() const { return params_; }
  Params &params() { return params_; }

  Output predict(const Input &x) const {
    L1 a1;
    L2 a2;
    return forward(x, a1, a2);
  }

  double loss(const Data &data) const {
    const int n = data.num_labels();
    OVTON_TON_CHECK(n > 0, "Mlp::loss: no labels");
    double sum = 0.0;
    for (int k = 0; k < n; ++k)
      sum += (predict(data.input(k)) - data.target(k)).squaredNorm();
    return sum / n;
  }

  /// MSE and its exact gradient. Samples are independent, so each is back-propagated right after its forward pass
  /// and nothing needs caching.
  double loss_and_gradient(const Data &data, Params &grad) const {
    const int n = data.num_labels();
    OVTON_TON_CHECK(n > 0, "Mlp::loss_and_gradient: no labels");
    grad.setZero();
    const auto W2 = block<H2, H1>(params_, kOffW2);
    const auto W3 = block<Out, H2>(params_, kOffW3);
    double sum = 0.0;
    const double scale = 2.0 / n;
    for (int k = 0; k < n; ++k) {
      const Input &x = data.input(k);
      L1 a1;
      L2 a2;
      const Output y = forward(x, a1, a2);
      const Output dy = scale * (y - data.target(k));
      sum += (y - data.target(k)).squaredNorm();
      block<Out, H2>(grad, kOffW3).noalias() += dy * a2.transpose();
      block<Out, 1>(grad, kOffB3) += dy;
      const L2 dz2 = (W3.transpose() * dy).cwiseProduct(L2::Ones() - a2.cwiseAbs2());
      block<H2, H1>(grad, kOffW2).noalias() += dz2 * a1.transpose();
      block<H2, 1>(grad, kOffB2) += dz2;
      const L1 dz1 = (W2.transpose() * dz2).cwiseProduct(L1::Ones() - a1.cwiseAbs2());
      block<H1, In>(grad, kOffW1).noalias() += dz1 * x.transpose();
      block<H1, 1>(grad, kOffB1) += dz1;
    }
    return sum / n;
  }

private:
  using L1 = Eigen::Matrix<double, H1, 1>;
  using L2 = Eigen::Matrix<double, H2, 1>;

  template <int R, int C, typename P> static auto block(P &p, int offset) {
    using M = Eigen::Matrix<double, R, C>;
    return Eigen::Map<std::conditional_t<std::is_const<P>::value, const M, M>>(p.data() + offset);
  }

  Output forward(const Input &x, L1 &a1, L2 &a2) const {
    a1 = block<H1, 1>(params_, kOffB1);
    a1.noalias() += block<H1, In>(params_, kOffW1) * x;
    a1 = a1.array().tanh().matrix();
    a2 = block<H2, 1>(params_, kOffB2);
    a2.noalias() += block<H2, H1>(params_, kOffW2) * a1;
    a2 = a2.array().tanh().matrix();
    Output y = block<Out, 1>(params_, kOffB3);
    y.noalias() += block<Out, H2>(params_, kOffW3) * a2;
    return y;
  }

  Params params_;
};

/// F2F-FVON, paper Table I: 3D position in camera frame (3) -> 5 -> 5 -> image velocity (2).
using F2fMlp = Mlp<3, 5, 5, 2>;

} // namespace ton
} // namespace ovton::msckf
