#pragma once
// One LSTM layer with a linear head on h, trained by hand-written backpropagation through time.
//
// Per step t (gates stacked i, f, g, o as in PyTorch's nn.LSTM):
//   a_t = W_x x_t + W_h h_{t-1} + b
//   i = sigma(a_i), f = sigma(a_f), g = tanh(a_g), o = sigma(a_o)
//   c_t = f * c_{t-1} + i * g,   h_t = o * tanh(c_t),   y_t = W_y h_t + b_y
// Loss (paper eq. 7 / 12): L = 1/n sum_t ||y_t - y*_t||^2 over all n labels of all sequences.
// The head is linear so that outputs may leave the [0,1] training range: TPN has to extrapolate a drift one step
// past the largest value in its window.
#include "ov_msckf_ton/ton/random_init.h"
#include "ov_msckf_ton/ton/sequence_set.h"
#include "ov_msckf_ton/ton/ton_error.h"

#include <Eigen/Core>
#include <cmath>
#include <random>
#include <type_traits>
#include <vector>

namespace ovton::msckf {
namespace ton {

template <int In, int Hidden, int Out> class Lstm {
public:
  static constexpr int kGates = 4 * Hidden;
  // Flat parameter layout (column-major blocks). Adam and the finite-difference tests see one vector.
  static constexpr int kOffWx = 0;
  static constexpr int kOffWh = kOffWx + kGates * In;
  static constexpr int kOffB = kOffWh + kGates * Hidden;
  static constexpr int kOffWy = kOffB + kGates;
  static constexpr int kOffBy = kOffWy + Out * Hidden;
  static constexpr int kNumParams = kOffBy + Out;

  using Params = Eigen::Matrix<double, kNumParams, 1>;
  using Input = Eigen::Matrix<double, In, 1>;
  using Output = Eigen::Matrix<double, Out, 1>;
  using Data = SequenceSet<In, Out>;

  Lstm() : params_(Params::Zero()) {}

  /// PyTorch's default initialisation (U(-1/sqrt(H), 1/sqrt(H)) for every LSTM weight, U(-1/sqrt(fan_in), ..) for
  /// the head), since the paper's networks were defined with those defaults.
  void init(std::mt19937 &rng) {
    const double k = 1.0 / std::sqrt(static_cast<double>(Hidden));
    fill_uniform(wx(params_), rng, k);
    fill_uniform(wh(params_), rng, k);
    fill_uniform(b(params_), rng, k);
    fill_uniform(wy(params_), rng, k);
    fill_uniform(by(params_), rng, k);
  }

  const Params &params() const { return params_; }
  Params &params() { return params_; }

  /// Recurrent state carried between steps; a default-constructed state is the zero state every sequence starts from.
  struct State {
    Eigen::Matrix<double, Hidden, 1> h = Eigen::Matrix<double, Hidden, 1>::Zero();
    Eigen::Matrix<double, Hidden, 1> c = Eigen::Matrix<double, Hidden, 1>::Zero();
  };

  /// One inference step: advances `state` by input `x` and returns the output. Lets callers feed a sequence without
  /// first copying it into a buffer.
  Output step(const Input &x, State &state) const {
    Step st;
    forward_step(x, state.h, state.c, st);
    state.h = st.h;
    state.c = st.c;
    return st.y;
  }

  /// Runs one sequence from zero state and returns the output of its last step.
  Output predict(const Input *xs, int len) const {
    OVTON_TON_CHECK(len > 0, "Lstm::predict: empty sequence");
    State state;
    Output y = Output::Zero();
    for (int t = 0; t < len; ++t)
      y = step(xs[t], state);
    return y;
  }

  /// MSE over all labels of `data` (no gradient).
  double loss(const Data &data) const {
    const int n = data.num_labels();
    OVTON_TON_CHECK(n > 0, "Lstm::loss: no labels");
    double sum = 0.0;
    Step st;
    for (int s = 0; s < data.num_sequences(); ++s) {
      Hid h = Hid::Zero(), c = Hid::Zero();
      for (int t = data.begin(s); t < data.end(s); ++t) {
        forward_step(data.input(t), h, c, st);
        h = st.h;
        c = st.c;
        sum += (st.y - data.target(t)).squaredNorm();
      }
    }
    return sum / n;
  }

  /// MSE and its exact gradient w.r.t. every parameter, by BPTT. The step cache grows to the largest data set seen
  /// and is reused afterwards, so repeated epochs do not allocate.
  double loss_and_gradient(const Data &data, Params &grad) {
    const int n = data.num_labels();
    OVTON_TON_CHECK(n > 0, "Lstm::loss_and_gradient: no labels");
    if (static_cast<int>(cache_.size()) < n)
      cache_.resize(n);
    grad.setZero();
    double sum = 0.0;
    const double scale = 2.0 / n;
    const auto Wy = wy(params_);
    const auto Wh = wh(params_);
    for (int s = 0; s < data.num_sequences(); ++s) {
      const int t0 = data.begin(s), t1 = data.end(s);
      Hid h = Hid::Zero(), c = Hid::Zero();
      for (int t = t0; t < t1; ++t) {
        forward_step(data.input(t), h, c, cache_[t]);
        h = cache_[t].h;
        c = cache_[t].c;
        sum += (cache_[t].y - data.target(t)).squaredNorm();
      }
      Hid dh_next = Hid::Zero(), dc_next = Hid::Zero();
      for (int t = t1 - 1; t >= t0; --t) {
        const Step &st = cache_[t];
        const Output dy = scale * (st.y - data.target(t));
        wy(grad).noalias() += dy * st.h.transpose();
        by(grad) += dy;
        const Hid dh = Wy.transpose() * dy + dh_next;
        const Hid dc = dh.cwiseProduct(st.o).cwiseProduct(Hid::Ones() - st.tanh_c.cwiseAbs2()) + dc_next;
        Gates da;
        da.template segment<Hidden>(0) = dc.cwiseProduct(st.g).cwiseProduct(st.i.cwiseProduct(Hid::Ones() - st.i));
        da.template segment<Hidden>(Hidden) =
            dc.cwiseProduct(st.c_prev).cwiseProduct(st.f.cwiseProduct(Hid::Ones() - st.f));
        da.template segment<Hidden>(2 * Hidden) = dc.cwiseProduct(st.i).cwiseProduct(Hid::Ones() - st.g.cwiseAbs2());
        da.template segment<Hidden>(3 * Hidden) =
            dh.cwiseProduct(st.tanh_c).cwiseProduct(st.o.cwiseProduct(Hid::Ones() - st.o));
        wx(grad).noalias() += da * st.x.transpose();
        wh(grad).noalias() += da * st.h_prev.transpose();
        b(grad) += da;
        dh_next.noalias() = Wh.transpose() * da;
        dc_next = dc.cwiseProduct(st.f);
      }
    }
    return sum / n;
  }

private:
  using Hid = Eigen::Matrix<double, Hidden, 1>;
  using Gates = Eigen::Matrix<double, kGates, 1>;

  struct Step {
    Input x;
    Hid h_prev, c_prev, i, f, g, o, c, tanh_c, h;
    Output y;
  };

  template <typename P> static auto wx(P &p) {
    return Eigen::Map<std::conditional_t<std::is_const<P>::value, const Eigen::Matrix<double, kGates, In>,
                                         Eigen::Matrix<double, kGates, In>>>(p.data() + kOffWx);
  }
  template <typename P> static auto wh(P &p) {
    return Eigen::Map<std::conditional_t<std::is_const<P>::value, const Eigen::Matrix<double, kGates, Hidden>,
                                         Eigen::Matrix<double, kGates, Hidden>>>(p.data() + kOffWh);
  }
  template <typename P> static auto b(P &p) {
    return Eigen::Map<std::conditional_t<std::is_const<P>::value, const Gates, Gates>>(p.data() + kOffB);
  }
  template <typename P> static auto wy(P &p) {
    return Eigen::Map<std::conditional_t<std::is_const<P>::value, const Eigen::Matrix<double, Out, Hidden>,
                                         Eigen::Matrix<double, Out, Hidden>>>(p.data() + kOffWy);
  }
  template <typename P> static auto by(P &p) {
    return Eigen::Map<std::conditional_t<std::is_const<P>::value, const Output, Output>>(p.data() + kOffBy);
  }

  static double sigmoid(double a) { return 1.0 / (1.0 + std::exp(-a)); }

  void forward_step(const Input &x, const Hid &h_prev, const Hid &c_prev, Step &st) const {
    const Params &p = params_;
    Gates a = b(p);
    a.noalias() += wx(p) * x;
    a.noalias() += wh(p) * h_prev;
    st.x = x;
    st.h_prev = h_prev;
    st.c_prev = c_prev;
    for (int k = 0; k < Hidden; ++k) {
      st.i[k] = sigmoid(a[k]);
      st.f[k] = sigmoid(a[Hidden + k]);
      st.g[k] = std::tanh(a[2 * Hidden + k]);
      st.o[k] = sigmoid(a[3 * Hidden + k]);
    }
    st.c = st.f.cwiseProduct(c_prev) + st.i.cwiseProduct(st.g);
    st.tanh_c = st.c.array().tanh().matrix();
    st.h = st.o.cwiseProduct(st.tanh_c);
    st.y = by(p);
    st.y.noalias() += wy(p) * st.h;
  }

  Params params_;
  std::vector<Step> cache_;
};

/// ITS-FVON, paper Table I: velocity (2) -> hidden 2 -> velocity (2).
using ItsLstm = Lstm<2, 2, 2>;
/// TPN, paper Table I: t_d (1) -> hidden 2 -> t_d (1).
using TpnLstm = Lstm<1, 2, 1>;

} // namespace ton
} // namespace ovton::msckf
