// Unit tests of the online networks' building blocks: exact gradients (finite differences on every weight), Adam,
// the min-max normaliser, warm start and seeded determinism.
#include "fd_check.h"
#include "ov_msckf_ton/ton/adam.h"
#include "ov_msckf_ton/ton/f2f_fvon.h"
#include "ov_msckf_ton/ton/its_fvon.h"
#include "ov_msckf_ton/ton/lstm.h"
#include "ov_msckf_ton/ton/min_max_normalizer.h"
#include "ov_msckf_ton/ton/mlp.h"
#include "ov_msckf_ton/ton/tpn.h"
#include "ov_msckf_ton/ton/trainer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using namespace ovton::msckf::ton;

namespace {

template <typename M> void random_fill(M &m, std::mt19937 &rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      m(r, c) = u(rng);
}

/// Central differences on every parameter; returns the largest error relative to max(|analytic|, |numeric|, floor).
/// The floor keeps near-zero gradients from reporting rounding noise as a large relative error.
template <typename Net> double max_gradient_error(Net &net, const typename Net::Data &data, int *worst_index) {
  typename Net::Params grad;
  net.loss_and_gradient(data, grad);
  const typename Net::Params p0 = net.params();
  const Eigen::MatrixXd fd = ovtest::numeric_jacobian(
      [&](const typename Net::Params &p) {
        net.params() = p;
        return Eigen::Matrix<double, 1, 1>(net.loss(data));
      },
      p0, 1e-5);
  net.params() = p0;
  double worst = 0.0;
  for (int k = 0; k < Net::kNumParams; ++k) {
    const double denom = std::max({std::abs(fd(0, k)), std::abs(grad[k]), 1e-3});
    const double err = std::abs(fd(0, k) - grad[k]) / denom;
    if (err > worst) {
      worst = err;
      *worst_index = k;
    }
  }
  return worst;
}

template <int In, int H, int Out> void check_lstm_gradient(unsigned seed) {
  using Net = Lstm<In, H, Out>;
  std::mt19937 rng(seed);
  Net net;
  // Wider than the default init so that gates sit away from their linear regime and every term of BPTT matters.
  random_fill(net.params(), rng, -1.5, 1.5);
  typename Net::Data data;
  for (int len : {1, 4, 7}) {
    data.begin_sequence();
    for (int t = 0; t < len; ++t) {
      typename Net::Input x;
      typename Net::Output y;
      random_fill(x, rng, -0.2, 1.2);
      random_fill(y, rng, -0.2, 1.2);
      data.push(x, y);
    }
  }
  typename Net::Params grad;
  net.loss_and_gradient(data, grad);
  EXPECT_NEAR(net.loss(data), net.loss_and_gradient(data, grad), 1e-15);
  // Every weight must receive gradient, otherwise a block is silently left out of BPTT.
  for (int k = 0; k < Net::kNumParams; ++k)
    EXPECT_NE(grad[k], 0.0) << "parameter " << k;
  int worst = -1;
  const double err = max_gradient_error(net, data, &worst);
  std::printf("LSTM(%d,%d,%d): %d weights, max relative gradient error %.2e (param %d)\n", In, H, Out, Net::kNumParams,
              err, worst);
  EXPECT_LT(err, 1e-6);
}

} // namespace

TEST(TonLstm, GradientMatchesFiniteDifferencesIts222) {
  static_assert(ItsLstm::kNumParams == 46, "LSTM(2,2,2): 16 Wx + 16 Wh + 8 b + 4 Wy + 2 by");
  check_lstm_gradient<2, 2, 2>(11);
  check_lstm_gradient<2, 2, 2>(12);
}

TEST(TonLstm, GradientMatchesFiniteDifferencesTpn121) {
  static_assert(TpnLstm::kNumParams == 35, "LSTM(1,2,1): 8 Wx + 16 Wh + 8 b + 2 Wy + 1 by");
  check_lstm_gradient<1, 2, 1>(21);
  check_lstm_gradient<1, 2, 1>(22);
}

TEST(TonMlp, GradientMatchesFiniteDifferences3552) {
  static_assert(F2fMlp::kNumParams == 62, "MLP(3,5,5,2): 15+5 + 25+5 + 10+2");
  for (unsigned seed : {31u, 32u}) {
    std::mt19937 rng(seed);
    F2fMlp net;
    random_fill(net.params(), rng, -1.5, 1.5);
    F2fMlp::Data data;
    for (int k = 0; k < 12; ++k) {
      F2fMlp::Input x;
      F2fMlp::Output y;
      random_fill(x, rng, 0.0, 1.0);
      random_fill(y, rng, 0.0, 1.0);
      data.push(x, y);
    }
    F2fMlp::Params grad;
    net.loss_and_gradient(data, grad);
    for (int k = 0; k < F2fMlp::kNumParams; ++k)
      EXPECT_NE(grad[k], 0.0) << "parameter " << k;
    int worst = -1;
    const double err = max_gradient_error(net, data, &worst);
    std::printf("MLP(3,5,5,2): %d weights, max relative gradient error %.2e (param %d)\n", F2fMlp::kNumParams, err,
                worst);
    EXPECT_LT(err, 1e-6);
  }
}

TEST(TonLstm, HiddenStateResetsBetweenSequences) {
  std::mt19937 rng(5);
  TpnLstm net;
  net.init(rng);
  TpnLstm::Input a(0.3), b(0.8);
  TpnLstm::Data both, only_b;
  both.begin_sequence();
  both.push(a, TpnLstm::Output(0.0));
  both.begin_sequence();
  both.push(b, TpnLstm::Output(0.0));
  only_b.begin_sequence();
  only_b.push(b, TpnLstm::Output(0.0));
  // Sequence 2 of `both` must not see sequence 1's state: its loss term equals the lone sequence's.
  const double ya = net.predict(&a, 1)[0], yb = net.predict(&b, 1)[0];
  EXPECT_NEAR(both.num_labels() * net.loss(both), ya * ya + yb * yb, 1e-15);
  EXPECT_NEAR(only_b.num_labels() * net.loss(only_b), yb * yb, 1e-15);
}

TEST(TonAdam, ConvergesOnIllConditionedQuadratic) {
  // f(x) = 1/2 sum_i a_i (x_i - c_i)^2 with a spread of 1e4 in curvature: Adam's per-coordinate scaling handles it.
  Adam<4>::Vec a(1e-2, 1.0, 10.0, 100.0), c(1.0, -2.0, 0.5, 3.0), x = Adam<4>::Vec::Zero();
  Adam<4> adam(0.05);
  auto f = [&](const Adam<4>::Vec &p) { return 0.5 * a.dot((p - c).cwiseAbs2()); };
  const double f0 = f(x);
  for (int k = 0; k < 3000; ++k)
    adam.step(x, a.cwiseProduct(x - c));
  EXPECT_LT(f(x), 1e-6 * f0);
  EXPECT_LT((x - c).cwiseAbs().maxCoeff(), 1e-2);
  EXPECT_EQ(adam.steps(), 3000);
  EXPECT_THROW(Adam<4>(-1.0), TonError);
}

TEST(TonAdam, TrainsLstmOnToySequence) {
  // Next-value prediction of a sampled sine: the loss must drop by an order of magnitude.
  std::mt19937 rng(7);
  TpnLstm net;
  net.init(rng);
  TpnLstm::Data data;
  data.begin_sequence();
  for (int t = 0; t < 25; ++t)
    data.push(TpnLstm::Input(0.5 + 0.4 * std::sin(0.4 * t)), TpnLstm::Output(0.5 + 0.4 * std::sin(0.4 * (t + 1))));
  Adam<TpnLstm::kNumParams> adam(1e-2);
  const TrainReport rep = train_network(net, adam, data, TrainOptions{1e-2, 800, 0.0});
  std::printf("toy LSTM: loss %.3e -> %.3e in %d epochs\n", rep.initial_loss, rep.final_loss, rep.epochs);
  EXPECT_EQ(rep.epochs, 800);
  EXPECT_FALSE(rep.converged);
  EXPECT_LT(rep.final_loss, 0.1 * rep.initial_loss);
  EXPECT_NEAR(rep.final_loss, net.loss(data), 1e-15);
}

TEST(TonTrainer, EarlyStopAtLossThreshold) {
  std::mt19937 rng(8);
  F2fMlp net;
  net.init(rng);
  F2fMlp::Data data;
  data.push(F2fMlp::Input(0.1, 0.2, 0.3), F2fMlp::Output(0.4, 0.6));
  Adam<F2fMlp::kNumParams> adam(1e-2);
  const TrainReport rep = train_network(net, adam, data, TrainOptions{1e-2, 5000, 1e-6});
  EXPECT_TRUE(rep.converged);
  EXPECT_LT(rep.epochs, 5000);
  EXPECT_LT(rep.final_loss, 1e-6);
  // Without labels nothing happens.
  const F2fMlp::Params before = net.params();
  const TrainReport none = train_network(net, adam, F2fMlp::Data(), TrainOptions{1e-2, 10, 0.0});
  EXPECT_EQ(none.epochs, 0);
  EXPECT_EQ(net.params(), before);
}

TEST(TonNormalizer, RoundTripAndUnitRange) {
  std::mt19937 rng(9);
  MinMaxNormalizer<3> norm;
  std::vector<Eigen::Vector3d> xs(20);
  for (auto &x : xs) {
    random_fill(x, rng, -50.0, 300.0);
    norm.add(x);
  }
  norm.finish();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = Eigen::Vector3d::Constant(-1e9);
  for (const auto &x : xs) {
    const Eigen::Vector3d n = norm.normalize(x);
    lo = lo.cwiseMin(n);
    hi = hi.cwiseMax(n);
    EXPECT_LT((norm.denormalize(n) - x).norm(), 1e-12 * x.norm());
  }
  EXPECT_LT(lo.cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((hi - Eigen::Vector3d::Ones()).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(TonNormalizer, ZeroRangeMapsToMiddleAndRoundTrips) {
  MinMaxNormalizer<2> norm(Eigen::Vector2d(1.0, 1e-3));
  norm.add(Eigen::Vector2d(5.0, -2.0));
  norm.add(Eigen::Vector2d(5.0, -2.0));
  norm.finish();
  const Eigen::Vector2d n = norm.normalize(Eigen::Vector2d(5.0, -2.0));
  EXPECT_NEAR(n[0], 0.5, 1e-15);
  EXPECT_NEAR(n[1], 0.5, 1e-12);
  EXPECT_TRUE(norm.scale().allFinite());
  EXPECT_NEAR(norm.denormalize(Eigen::Vector2d(0.6, 0.6))[0], 5.1, 1e-12);
  EXPECT_NEAR(norm.denormalize(Eigen::Vector2d(0.6, 0.6))[1], -2.0 + 1e-4, 1e-12);
  const Eigen::Vector2d back = norm.denormalize(norm.normalize(Eigen::Vector2d(7.0, 3.0)));
  EXPECT_NEAR(back[0], 7.0, 1e-12);
  EXPECT_NEAR(back[1], 3.0, 1e-12);
}

TEST(TonNormalizer, RejectsMisuse) {
  MinMaxNormalizer<1> norm;
  EXPECT_THROW(norm.normalize(Eigen::Matrix<double, 1, 1>(1.0)), TonError);
  EXPECT_THROW(norm.finish(), TonError);
  EXPECT_THROW(norm.add(Eigen::Matrix<double, 1, 1>(std::numeric_limits<double>::quiet_NaN())), TonError);
}

TEST(TonWrappers, WarmStartAndDeterminism) {
  TpnOptions opt;
  opt.train.max_epochs = 50;
  Tpn a(opt), b(opt);
  for (int k = 0; k < 10; ++k) {
    a.push_estimate(0.01 + 1e-5 * k);
    b.push_estimate(0.01 + 1e-5 * k);
  }
  const TrainReport r1 = a.train();
  b.train();
  EXPECT_EQ(a.network().params(), b.network().params()); // same seed, same data -> same weights
  // Same window again: training resumes where it stopped instead of restarting from the initial weights.
  const TrainReport r2 = a.train();
  EXPECT_EQ(r1.epochs, 50);
  EXPECT_NEAR(r2.initial_loss, r1.final_loss, 1e-15);
  EXPECT_LT(r2.final_loss, r1.final_loss);
  a.reset();
  EXPECT_EQ(a.num_labels(), 0);
  EXPECT_FALSE(a.trained());
}

TEST(TonWrappers, BufferAndMisuse) {
  Tpn tpn;
  EXPECT_THROW(tpn.predict(), TonError);
  EXPECT_EQ(tpn.train().epochs, 0); // no labels: nothing to learn, no throw
  for (int k = 0; k < 45; ++k)
    tpn.push_estimate(k * 1e-3);
  EXPECT_EQ(tpn.num_labels(), 30);
  EXPECT_DOUBLE_EQ(tpn.labels().front(), 15e-3);
  EXPECT_THROW(tpn.push_estimate(std::nan("")), TonError);

  ItsFvon its;
  EXPECT_THROW(its.predict(std::vector<Eigen::Vector2d>{Eigen::Vector2d(1, 2)}), TonError);
  its.add_track(std::vector<Eigen::Vector2d>{Eigen::Vector2d(1, 2)}); // too short to carry a pair
  EXPECT_EQ(its.num_tracks(), 0);

  F2fFvon f2f;
  EXPECT_THROW(f2f.predict(Eigen::Vector3d(0, 0, 1)), TonError);
  EXPECT_THROW(f2f.add_label(Eigen::Vector3d(0, 0, std::nan("")), Eigen::Vector2d::Zero()), TonError);
}
