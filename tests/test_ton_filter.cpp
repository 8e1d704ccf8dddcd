// FVON and TPN inside the filter (paper Algorithm 1): on a short feature-level simulation, FVON gives features whose
// first observation has no tracked velocity a t_d constraint, the networks' cost is reported, and TPN drives the
// t_d mean between images.
#include "estimator_test_util.h"
#include "ov_core/io/dataset.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_sim/simulator.h"
#include "test_util.h"

#include <cmath>
#include <iostream>
#include <memory>

using namespace ovton::msckf;

namespace {

struct ModeRun {
  VioCounters counters;
  StageTimes times;
  FvonStats fvon;
  /// Per processed image K, in order: the filter's t̂_d(K) after its update, and TPN's t_d^TPN(K+1) made right
  /// after it (NaN before TPN has enough labels).
  std::vector<double> td_hat, tpn_next;
  long tpn_clamped = 0;
};

ModeRun run_mode(const ovton::core::Dataset &data, TdMode mode, const VioOptions &base = VioOptions()) {
  VioOptions opt = base;
  opt.td.mode = mode;
  opt.init.mode = InitMode::GroundTruth;
  opt.td.search.enabled = false; // the filter alone, from the configured t_d
  ModeRun r;
  const auto run =
      ovtest::run_estimator(data, opt, {ovtest::peek([&](const VioManager &f) {
                              r.td_hat.push_back(f.state().td);
                              const TpnDriver *t = f.tpn();
                              r.tpn_next.push_back(t && t->has_prediction() ? t->prediction() : std::nan(""));
                              if (f.fvon())
                                r.fvon = f.fvon()->stats();
                              r.tpn_clamped = f.td_model().stats().rate_clamped;
                            })});
  EXPECT_FALSE(run.traj.empty()) << run.report.init_message;
  EXPECT_EQ(run.report.counters.images_before_init, 0);
  r.counters = run.report.counters;
  r.times = run.report.times;
  return r;
}

std::unique_ptr<ovton::core::Dataset> simulate(const ovtest::TempDir &dir, ovton::sim::TdModelOptions td,
                                               double duration_s, double pixel_noise = 1.0) {
  ovton::sim::SimOptions o;
  o.out_dir = dir / "sim";
  o.duration_s = duration_s;
  o.seed = 11;
  o.features_only = true;
  o.td = td;
  o.features.pixel_noise = pixel_noise;
  ovton::sim::write_simulation(o);
  return std::make_unique<ovton::core::Dataset>(ovton::core::load_dataset(o.out_dir));
}

/// The 8 s, constant +10 ms simulation the FVON tests share.
std::unique_ptr<ovton::core::Dataset> simulate_constant_10ms(const ovtest::TempDir &dir) {
  ovton::sim::TdModelOptions td;
  td.kind = ovton::sim::TdModelKind::Constant;
  td.td0_s = 0.010;
  return simulate(dir, td, 8.0);
}

/// Fewer epochs than Table I keep the suite fast; the counts checked here do not depend on how well the networks
/// fit, only on FVON supplying a velocity where the constant-speed model has none.
VioOptions fast_networks() {
  VioOptions o;
  o.ton.fvon.its.train.max_epochs = 200;
  o.ton.fvon.f2f.train.max_epochs = 300;
  o.ton.tpn.tpn.train.max_epochs = 300;
  return o;
}

} // namespace

TEST(TonFilter, FvonGivesMoreFeaturesATdConstraintThanSir) {
  ovtest::TempDir dir;
  const auto data = simulate_constant_10ms(dir);

  // The paper's SIR gives a new feature's first observation no velocity; FVON's job is to give it one. (With the
  // default first_velocity: next, sir gets one from the next observation too.)
  VioOptions paper_sir = fast_networks();
  paper_sir.td.first_velocity = FirstVelocity::None;
  const ModeRun sir = run_mode(*data, TdMode::Sir, paper_sir);
  const ModeRun fvon = run_mode(*data, TdMode::Fvon, paper_sir);
  const ModeRun ton = run_mode(*data, TdMode::Ton, paper_sir);
  for (const auto *p : {&sir, &fvon, &ton}) {
    const VioCounters &c = p->counters;
    std::cout << "[ton filter] t_d rows " << c.td_rows << " (tracked " << c.td_rows_by_source[kVelocityTracked]
              << ", ITS " << c.td_rows_by_source[kVelocityItsFvon] << ", F2F " << c.td_rows_by_source[kVelocityF2fFvon]
              << "), features with t_d " << c.td_features << " of " << c.features_used << ", networks "
              << p->times.networks / std::max(1L, p->times.frames) << " ms/frame; final t_d " << p->td_hat.back() * 1e3
              << " ms\n";
  }
  std::cout << "[ton filter] fvon: ITS trained " << fvon.fvon.its_trainings << "x, F2F " << fvon.fvon.f2f_trainings
            << "x; predictions ITS " << fvon.fvon.its_predictions << ", F2F " << fvon.fvon.f2f_predictions << ", none "
            << fvon.fvon.no_prediction << ", gated " << fvon.fvon.gated << "\n";

  // sir: only tracked velocities exist.
  EXPECT_EQ(sir.counters.td_rows_by_source[kVelocityItsFvon], 0);
  EXPECT_EQ(sir.counters.td_rows_by_source[kVelocityF2fFvon], 0);
  EXPECT_EQ(sir.times.networks, 0.0);
  for (const auto *p : {&fvon, &ton}) {
    const VioCounters &c = p->counters;
    EXPECT_GT(c.td_rows, sir.counters.td_rows);
    EXPECT_GT(c.td_features, sir.counters.td_features);
    EXPECT_GT(c.td_rows_by_source[kVelocityItsFvon], 0);
    EXPECT_GT(c.td_rows_by_source[kVelocityF2fFvon], 0);
    EXPECT_GT(p->times.networks, 0.0);
    // A first observation that got a velocity enables t_d on the feature's other rows too, which are tracked.
    EXPECT_EQ(c.td_rows, c.td_rows_by_source[kVelocityTracked] + c.td_rows_by_source[kVelocityItsFvon] +
                             c.td_rows_by_source[kVelocityF2fFvon]);
  }
  // TPN is off in fvon, and runs after every image in ton.
  EXPECT_TRUE(std::isnan(fvon.tpn_next.back()));
  EXPECT_TRUE(std::isfinite(ton.tpn_next.back()));
}

TEST(TonFilter, FvonGateKeepsOnlyPredictionsThatAgreeWithTheTrack) {
  ovtest::TempDir dir;
  const auto data = simulate_constant_10ms(dir);
  VioOptions open = fast_networks(), shut = fast_networks(), normal = fast_networks();
  open.ton.fvon.gate_px_s = 0.0;  // no check
  shut.ton.fvon.gate_px_s = 1e-6; // nothing agrees this well with a noisy track
  const ModeRun a = run_mode(*data, TdMode::Fvon, open);
  const ModeRun b = run_mode(*data, TdMode::Fvon, shut);
  const ModeRun c = run_mode(*data, TdMode::Fvon, normal);
  std::cout << "[fvon gate] predictions " << c.fvon.its_predictions + c.fvon.f2f_predictions << ", gated at 80 px/s "
            << c.fvon.gated << "; network t_d rows: no gate "
            << a.counters.td_rows_by_source[kVelocityItsFvon] + a.counters.td_rows_by_source[kVelocityF2fFvon]
            << ", 80 px/s "
            << c.counters.td_rows_by_source[kVelocityItsFvon] + c.counters.td_rows_by_source[kVelocityF2fFvon] << "\n";
  EXPECT_EQ(a.fvon.gated, 0);
  EXPECT_GT(a.counters.td_rows_by_source[kVelocityF2fFvon] + a.counters.td_rows_by_source[kVelocityItsFvon], 0);
  // Every first observation of an updated feature has a measured next velocity, so a shut gate drops them all.
  EXPECT_EQ(b.fvon.gated, b.fvon.its_predictions + b.fvon.f2f_predictions);
  EXPECT_EQ(b.counters.td_rows_by_source[kVelocityItsFvon] + b.counters.td_rows_by_source[kVelocityF2fFvon], 0);
  // The default discriminates: some predictions pass, some do not (measured here: about a third pass, i.e. most
  // predictions of these briefly trained networks are more than 80 px/s from the track's next velocity).
  EXPECT_GT(c.counters.td_rows_by_source[kVelocityF2fFvon] + c.counters.td_rows_by_source[kVelocityItsFvon], 0);
  EXPECT_GT(c.fvon.gated, 0);
  EXPECT_LT(c.fvon.gated, c.fvon.its_predictions + c.fvon.f2f_predictions);
}

namespace {

struct PredictionErrors {
  double tpn = 0, last = 0; ///< mean |error| [s]
  long n = 0;
};

/// TPN's t_d^TPN(K) against predicting the last estimate t̂_d(K−1), both scored against `reference(K)`.
template <typename Ref> PredictionErrors prediction_errors(const ModeRun &r, Ref reference) {
  PredictionErrors e;
  for (size_t k = 1; k < r.td_hat.size(); ++k) {
    if (!std::isfinite(r.tpn_next[k - 1]))
      continue;
    e.tpn += std::abs(r.tpn_next[k - 1] - reference(k));
    e.last += std::abs(r.td_hat[k - 1] - reference(k));
    ++e.n;
  }
  if (e.n) {
    e.tpn /= e.n;
    e.last /= e.n;
  }
  return e;
}

} // namespace

TEST(TonFilter, TpnOnNoiseFreeDrift) {
  ovtest::TempDir dir;
  ovton::sim::TdModelOptions td;
  td.kind = ovton::sim::TdModelKind::Drift;
  td.td0_s = 0.010;
  td.bias_s_per_s = 1e-4;
  td.noise_s_per_sqrt_s = 0.0;
  // KLT-like 0.3 px: at 1 px the image-plane estimate of this gentle 8 s flight never gets below TPN's start sigma.
  const auto data = simulate(dir, td, 8.0, 0.3);
  const auto truth = [&](size_t k) { return data->td_truth_at(data->images[k].t_cam_ns); };

  // TPN in the loop (mode tpn): its prediction becomes the prior mean of t_d at the next image, so scoring it
  // against the next posterior t̂_d(K) is circular (the posterior starts from it). Only the truth is a fair
  // reference here, and it is printed, not asserted: the sir estimate this runs on is biased by far more than the
  // 5 us per frame the offset drifts (see the report in the output), so neither predictor is near the truth.
  // A label and a prediction per image, as in the paper (the default's 10-image labels predict per block).
  VioOptions per_image = fast_networks();
  per_image.ton.tpn_label_images = 1;
  const ModeRun tpn = run_mode(*data, TdMode::Tpn, per_image);
  ASSERT_GT(tpn.td_hat.size(), 100u);
  const PredictionErrors loop_truth = prediction_errors(tpn, truth);
  std::cout << "[ton filter] tpn mode, " << loop_truth.n << " predictions: mean |t_d^TPN(K) - truth(K)| "
            << loop_truth.tpn * 1e6 << " us, last value " << loop_truth.last * 1e6 << " us; rate clamped "
            << tpn.tpn_clamped << "x; networks " << tpn.times.networks / std::max(1L, tpn.times.frames)
            << " ms/frame; final t_d " << tpn.td_hat.back() * 1e3 << " ms, truth " << truth(tpn.td_hat.size() - 1) * 1e3
            << " ms\n";
  EXPECT_GT(loop_truth.n, 50);
  EXPECT_GT(tpn.times.networks, 0.0);

  // TPN as a predictor of the filter's own estimate sequence, without feedback: a TpnDriver fed the estimates of a
  // sir run (as the filter feeds it) predicts t̂_d(K) from t̂_d(..K−1); that is what it is trained to do. Against
  // the truth it is printed only, for the reason above.
  VioOptions opt = fast_networks();
  opt.td.mode = TdMode::Sir;
  opt.init.mode = InitMode::GroundTruth;
  opt.td.search.enabled = false;
  // Table I's 1000 epochs per frame, as the filter uses by default (fast_networks() lowers them for speed).
  TpnDriver shadow{TpnDriverOptions()};
  ModeRun sir;
  for (const auto &st : ovtest::run_estimator(*data, opt).traj) {
    sir.td_hat.push_back(st.td_s);
    shadow.step(st.td_s);
    sir.tpn_next.push_back(shadow.has_prediction() ? shadow.prediction() : std::nan(""));
  }
  const PredictionErrors open_est = prediction_errors(sir, [&](size_t k) { return sir.td_hat[k]; });
  const PredictionErrors open_truth = prediction_errors(sir, truth);
  std::cout << "[ton filter] TPN beside sir, " << open_est.n << " predictions: mean |t_d^TPN(K) - t_d(K)| "
            << open_est.tpn * 1e6 << " us, last value " << open_est.last * 1e6 << " us; against truth "
            << open_truth.tpn * 1e6 << " us, last value " << open_truth.last * 1e6 << " us\n";
  // Not asserted: TPN < last value does not hold reliably on these estimates. The sir estimate runs away by tens of
  // ms with ~0.6 ms jumps per update (velocity noise), and whether the LSTM's extrapolation of that beats the last
  // value flipped between updater revisions (560 vs 623 us, then 629 vs 600 us). TPN beating the last value on a
  // clean drift is asserted at the network level (test_ton_vs_rules.cpp); in the filter it is reported.
  EXPECT_GT(open_est.n, 50);
  EXPECT_TRUE(std::isfinite(open_est.tpn));
}
