// Time-offset process models (ov_msckf_ton/td/): the drift state's covariance propagation, where each model puts t_d
// at the next image, and consistency (t_d NEES) of the models in a scalar filter that observes t_d directly.
#include "ov_core/math/so3.h"
#include "ov_eval/nees.h"
#include "ov_msckf_ton/state/state_helper.h"
#include "ov_msckf_ton/td/td_model.h"
#include "ov_msckf_ton/td/td_models.h"
#include "ov_msckf_ton/td/td_noise_adapter.h"
#include "test_util.h"

#include <Eigen/Cholesky>
#include <iostream>
#include <random>

using namespace ovton::msckf;

namespace {

VioOptions with_process(TdMode mode, TdProcess process) {
  VioOptions o;
  o.td.mode = mode;
  o.td.process = process;
  return o;
}

/// A State with an IMU block, t_d, and (for the drift model) its rate, initialised as the VioManager does.
State initialised_state(TdModel &m, double td_sigma) {
  State s(true);
  s.P.diagonal().setConstant(1e-4);
  s.P(s.td_index, s.td_index) = td_sigma * td_sigma;
  m.initialize(s);
  return s;
}

} // namespace

TEST(TdModels, DriftCovariancePropagationIsPhiPPhiTPlusQ) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  State s(true);
  s.td_rate_index = s.add_variable(Eigen::MatrixXd::Constant(1, 1, 1e-6));
  Eigen::MatrixXd A(s.dim(), s.dim());
  for (int i = 0; i < A.rows(); ++i)
    for (int j = 0; j < A.cols(); ++j)
      A(i, j) = n(rng);
  s.P = A * A.transpose();
  const Eigen::MatrixXd P0 = s.P;
  const double dt = 0.05, q_td = 2e-4, q_r = 3e-5;
  propagate_td_covariance(s, q_td, q_r, dt);
  Eigen::MatrixXd Phi = Eigen::MatrixXd::Identity(s.dim(), s.dim());
  Phi(s.td_index, s.td_rate_index) = dt;
  Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(s.dim(), s.dim());
  Q(s.td_index, s.td_index) = q_td * q_td * dt + q_r * q_r * dt * dt * dt / 3;
  Q(s.td_index, s.td_rate_index) = Q(s.td_rate_index, s.td_index) = q_r * q_r * dt * dt / 2;
  Q(s.td_rate_index, s.td_rate_index) = q_r * q_r * dt;
  const Eigen::MatrixXd expected = Phi * P0 * Phi.transpose() + Q;
  EXPECT_LT((s.P - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
  // A clone marginalised in front of the rate keeps its index pointing at the rate.
  state_helper::clone(s, 1, false, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  const double var_rate = s.P(s.td_rate_index, s.td_rate_index);
  state_helper::marginalize_clone(s, 1);
  EXPECT_EQ(s.P(s.td_rate_index, s.td_rate_index), var_rate);
}

TEST(TdModels, EachModelPutsTdWhereItsPropagationEnds) {
  // Drift: t_d(end) must equal t_d + rate * (t_cam + t_d(end) - t_state), the interval actually propagated.
  VioOptions o = with_process(TdMode::Drift, TdProcess::Auto);
  auto drift = make_td_model(o);
  ASSERT_EQ(drift->kind(), TdProcess::Drift);
  State s = initialised_state(*drift, 0.01);
  ASSERT_GE(s.td_rate_index, 0);
  s.t_imu_ns = 1000000000;
  s.td = 0.012;
  s.td_rate = 2e-4;
  const int64_t t_cam = 1050000000;
  const double td_end = drift->td_at_image(s, t_cam, 1000000000);
  const double dt = ovton::core::ns_to_s(t_cam - s.t_imu_ns) + td_end;
  EXPECT_NEAR(td_end, s.td + s.td_rate * dt, 1e-15);
  drift->propagate(s, td_end, dt);
  EXPECT_NEAR(s.td, td_end, 1e-15);
  // Constant: t_d stays; its variance does not grow. Random walk: it grows by q^2 dt.
  auto constant = make_td_model(with_process(TdMode::Sr, TdProcess::Auto));
  EXPECT_EQ(constant->kind(), TdProcess::Constant);
  State c = initialised_state(*constant, 0.01);
  const double v0 = c.td_variance();
  constant->propagate(c, constant->td_at_image(c, t_cam, -1), 0.05);
  EXPECT_EQ(c.td_variance(), v0);
  VioOptions rw_opt = with_process(TdMode::Sr, TdProcess::RandomWalk);
  rw_opt.td.random_walk = 1e-3;
  auto rw = make_td_model(rw_opt);
  State r = initialised_state(*rw, 0.01);
  rw->propagate(r, r.td, 0.05);
  EXPECT_NEAR(r.td_variance() - v0, 1e-6 * 0.05, 1e-18);
  // Oracle needs the truth and reads it.
  EXPECT_THROW(make_td_model(with_process(TdMode::Oracle, TdProcess::Auto)), ovton::core::UsageError);
  auto oracle = make_td_model(with_process(TdMode::Oracle, TdProcess::Auto), [](int64_t t) { return 1e-12 * t; });
  EXPECT_DOUBLE_EQ(oracle->td_at_image(r, 5000000000, -1), 5e-3);
}

namespace {

/// A scalar filter around the State: t_d is observed directly with noise sigma_z at 20 Hz while the truth follows
/// the paper's eq. 4 (constant drift plus random walk). Returns the average t_d NEES and the final error.
struct ScalarRun {
  double nees = 0, final_err = 0, final_rate = 0;
};
ScalarRun run_scalar(const VioOptions &o, double drift, double q_true, double sigma_z, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, 1);
  auto model = make_td_model(o);
  State s = initialised_state(*model, 0.01);
  double truth = 0.01 + 0.01 * n(rng); // prior error drawn from the prior
  const double dt = 0.05;
  ScalarRun r;
  int counted = 0;
  for (int k = 0; k < 2000; ++k) { // 100 s
    truth += drift * dt + q_true * std::sqrt(dt) * n(rng);
    const int64_t t_cam = static_cast<int64_t>((k + 1) * dt * 1e9);
    const double td_end = model->td_at_image(s, t_cam, k == 0 ? -1 : t_cam - 50000000);
    model->propagate(s, td_end, dt);
    s.t_imu_ns = t_cam;
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(1, s.dim());
    H(0, s.td_index) = 1;
    const double td0 = s.td, v0 = s.td_variance();
    state_helper::ekf_update(s, H, Eigen::VectorXd::Constant(1, truth + sigma_z * n(rng) - s.td), sigma_z * sigma_z);
    model->after_update(td0, v0, s.td, s.td_variance());
    model->after_image(s, t_cam);
    if (k >= 200) { // after 10 s
      const double e = truth - s.td;
      r.nees += e * e / s.td_variance();
      ++counted;
    }
  }
  r.nees /= counted;
  r.final_err = truth - s.td;
  r.final_rate = s.td_rate;
  return r;
}

double mean_nees(const VioOptions &o, double drift, double q_true, double sigma_z) {
  double sum = 0;
  for (unsigned seed = 1; seed <= 10; ++seed)
    sum += run_scalar(o, drift, q_true, sigma_z, seed).nees;
  return sum / 10;
}

} // namespace

TEST(TdModels, DriftStateIsConsistentAndFindsTheRate) {
  // The paper's drift: 0.1 ms/s bias, 0.1 ms/sqrt(s) noise; t_d observed to 0.2 ms per image.
  VioOptions o = with_process(TdMode::Drift, TdProcess::Auto);
  o.td.random_walk = 1e-4;
  o.td.rate_random_walk = 1e-6;
  o.td.adaptive_noise = false;
  const double nees = mean_nees(o, 1e-4, 1e-4, 2e-4);
  std::cout << "[td models] drift state: t_d NEES " << nees << " (1 is ideal)\n";
  EXPECT_GT(nees, 0.6);
  EXPECT_LT(nees, 1.5);
  const ScalarRun r = run_scalar(o, 1e-4, 1e-4, 2e-4, 1);
  EXPECT_NEAR(r.final_rate, 1e-4, 3e-5) << "the rate state should learn the 0.1 ms/s drift";
}

TEST(TdModels, AdaptiveNoiseMakesAnUnderestimatedRandomWalkHonestOnADriftingOffset) {
  // A random walk far too small for a drifting offset is over-confident (its variance shrinks while the truth walks
  // away); covariance matching grows the process noise until the corrections fit the variance.
  VioOptions fixed = with_process(TdMode::Sr, TdProcess::RandomWalk), adaptive = fixed;
  fixed.td.random_walk = adaptive.td.random_walk = 1e-7;
  fixed.td.adaptive_noise = false;
  adaptive.td.adaptive_noise = true;
  const double nees_fixed = mean_nees(fixed, 1e-4, 1e-4, 2e-4);
  const double nees_adaptive = mean_nees(adaptive, 1e-4, 1e-4, 2e-4);
  std::cout << "[td models] 0.1 us/sqrt(s) random walk on the paper's drift: t_d NEES " << nees_fixed << " fixed, "
            << nees_adaptive << " adaptive (1 is ideal)\n";
  EXPECT_GT(nees_fixed, 20.0);
  EXPECT_LT(nees_adaptive, 2.0);
  EXPECT_GT(nees_adaptive, 0.5);
}

TEST(TdModels, BlockNoiseAdapterSeesALagThePerImageSamplesMiss) {
  // The adapter fed the corrections of a filter at steady state (each image adds q0²·dt and its update removes it)
  // whose prediction trails the offset by r = 0.1 ms/s: every image's correction is the white part plus r·dt.
  // Per image the trend adds r²·dt to the sample (1/40 of q0²: invisible); summed over T-s blocks it adds r²·T.
  const double q0 = 2e-4, dt = 0.05, r = 1e-4, v = q0 * q0 * dt, T = 3.0;
  double q2_image[2], q2_block[2]; // white, trailing
  for (const int trailing : {0, 1}) {
    TdNoiseAdapter per_image(q0), block(q0, T);
    std::mt19937 rng(7);
    std::normal_distribution<double> n(0, 1);
    double sum_image = 0, sum_block = 0;
    int count = 0;
    for (int k = 0; k < 20000; ++k) { // 1000 s
      const double d = std::sqrt(v) * n(rng) + trailing * r * dt;
      for (TdNoiseAdapter *a : {&per_image, &block}) {
        a->add_process(v);
        a->add_update(0.0, 2 * v, d, v);
        a->close_image(dt);
      }
      if (k >= 2000) {
        sum_image += per_image.q() * per_image.q();
        sum_block += block.q() * block.q();
        ++count;
      }
    }
    q2_image[trailing] = sum_image / count;
    q2_block[trailing] = sum_block / count;
    std::cout << "[td models] adapter on " << (trailing ? "trailing" : "white") << " corrections: q "
              << std::sqrt(q2_image[trailing]) * 1e3 << " ms/sqrt(s) per image, " << std::sqrt(q2_block[trailing]) * 1e3
              << " over 3-s blocks (floor 0.2)\n";
  }
  // White corrections: both near the floor, the blocks above it by the noise of their mean (the floor clips it).
  EXPECT_LT(q2_image[0], 1.1 * q0 * q0);
  EXPECT_LT(q2_block[0], 1.4 * q0 * q0);
  // Trailing ones add r²·dt per image (invisible) and r²·T over a block.
  EXPECT_LT(q2_image[1] - q2_image[0], 0.1 * r * r * T);
  EXPECT_NEAR(q2_block[1] - q2_block[0], r * r * T, 0.25 * r * r * T);
  // In a filter whose random walk is the truth's, the blocks must not make it under-confident.
  VioOptions honest = with_process(TdMode::Sr, TdProcess::RandomWalk);
  honest.td.random_walk = 1e-4;
  honest.td.adaptive_block_s = T;
  const double nees_rw = mean_nees(honest, 0.0, 1e-4, 2e-4);
  std::cout << "[td models] true 0.1 ms/sqrt(s) random walk, 3-s blocks: t_d NEES " << nees_rw << "\n";
  EXPECT_GT(nees_rw, 0.6);
  EXPECT_LT(nees_rw, 1.5);
}

// TPN learns from the filter's estimates. Per image they jitter by more than a drift moves them (here 0.05 ms against
// 0.025 ms per image), and a label per image (the paper) teaches the LSTM the jitter's mean reversion instead of the
// trend; labels that are means over ton.tpn_label_images images recover it.
TEST(TdModels, TpnBlockLabelsFindTheRateUnderPerImageJitter) {
  const double rate = 5e-4, dt = 0.05, jitter = 5e-5;
  double mean_rate[2] = {0, 0};
  for (int M : {1, 10}) {
    VioOptions o = with_process(TdMode::Tpn, TdProcess::Auto);
    o.ton.tpn_label_images = M;
    o.td.adaptive_noise = false;
    auto m = make_td_model(o);
    State s = initialised_state(*m, 1e-4);
    std::mt19937 rng(5);
    std::normal_distribution<double> n(0, jitter);
    double sum = 0;
    int cnt = 0;
    const int64_t t0 = 1'000'000'000, step = 50'000'000;
    for (int k = 0; k < 800; ++k) {
      s.td = 0.01 + rate * dt * k + n(rng); // the filter's estimate after image k
      m->after_image(s, t0 + k * step);
      const double next = m->td_at_image(s, t0 + (k + 1) * step, t0 + k * step);
      if (k >= 400) {
        sum += (next - s.td) / dt;
        ++cnt;
      }
    }
    mean_rate[M == 1 ? 0 : 1] = sum / cnt;
    if (M > 1) {
      // Converging again (σ above ton.tpn_start_sigma_s): no drive at the old labels' rate until new labels come.
      s.P(s.td_index, s.td_index) = 4e-6;
      m->after_image(s, t0 + 800 * step);
      EXPECT_EQ(m->td_at_image(s, t0 + 801 * step, t0 + 800 * step), s.td);
    }
  }
  std::cout << "[ TPN labels ] true rate 0.5 ms/s, jitter 0.05 ms per image: propagated rate " << mean_rate[0] * 1e3
            << " ms/s with a label per image, " << mean_rate[1] * 1e3 << " ms/s with 10-image labels\n";
  EXPECT_LT(std::abs(mean_rate[1] - rate), 0.15 * rate);
  // The scenario must be one where the jitter matters, or the test would not show what the block labels fix.
  EXPECT_GT(std::abs(mean_rate[0] - rate), 0.3 * rate) << "per-image labels were expected to miss the trend";
}

TEST(TdModels, NoiseAdapterConvergesToTheTrueRandomWalk) {
  VioOptions o = with_process(TdMode::Sr, TdProcess::RandomWalk);
  o.td.random_walk = 1e-5; // ten times too small; the floor
  o.td.adaptive_noise = true;
  auto model = make_td_model(o);
  // Drive the scalar filter and read the adapted sigma.
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 1);
  State s = initialised_state(*model, 0.01);
  double truth = s.td, q_sum = 0;
  int q_count = 0;
  for (int k = 0; k < 4000; ++k) {
    truth += 3e-4 * std::sqrt(0.05) * n(rng);
    model->propagate(s, s.td, 0.05);
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(1, s.dim());
    H(0, s.td_index) = 1;
    const double td0 = s.td, v0 = s.td_variance();
    state_helper::ekf_update(s, H, Eigen::VectorXd::Constant(1, truth + 2e-4 * n(rng) - s.td), 4e-8);
    model->after_update(td0, v0, s.td, s.td_variance());
    model->after_image(s, k);
    if (k >= 1000) {
      q_sum += model->stats().process_sigma;
      ++q_count;
    }
  }
  const double q_mean = q_sum / q_count;
  std::cout << "[td models] adapted random walk " << q_mean * 1e3 << " ms/sqrt(s) for a true 0.3\n";
  EXPECT_NEAR(q_mean, 3e-4, 0.6e-4);
}

TEST(Nees, SamplesDrawnFromTheCovarianceAverageTheirDimension) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0, 1);
  std::vector<ovton::core::StateSample> gt(2);
  gt[0].t_ns = 0;
  gt[1].t_ns = 2000000000;
  gt[1].p = Eigen::Vector3d(1, 0, 0);
  std::vector<ovton::core::TdSample> td_truth = {{0, 0.01}, {2000000000, 0.01}};
  ovton::eval::NeesAccumulator acc(gt, td_truth);
  Eigen::Matrix<double, 6, 6> A;
  for (int i = 0; i < 36; ++i)
    A(i / 6, i % 6) = 0.01 * n(rng);
  const Eigen::Matrix<double, 6, 6> P = A * A.transpose() + 1e-6 * Eigen::Matrix<double, 6, 6>::Identity();
  const Eigen::Matrix<double, 6, 6> L = P.llt().matrixL();
  for (int k = 0; k < 4000; ++k) {
    ovton::core::StateSample e;
    e.t_ns = 1000000000;
    Eigen::Matrix<double, 6, 1> z;
    for (int i = 0; i < 6; ++i)
      z(i) = n(rng);
    const Eigen::Matrix<double, 6, 1> err = L * z; // truth = estimate + err
    e.p = Eigen::Vector3d(0.5, 0, 0) - err.tail<3>();
    e.q_WB = Eigen::Quaterniond(ovton::core::so3_exp(-err.head<3>()));
    e.P_pose = P;
    e.has_pose_cov = true;
    e.has_td = true;
    e.td_sigma_s = 1e-4;
    e.td_s = 0.01 + 1e-4 * n(rng);
    acc.add(e);
  }
  EXPECT_NEAR(acc.stats().ori(), 3.0, 0.25);
  EXPECT_NEAR(acc.stats().pos(), 3.0, 0.25);
  EXPECT_NEAR(acc.stats().td(), 1.0, 0.1);
}

TEST(TdModels, CloneTrendGivesAnOlderCloneTheOffsetOfItsOwnImage) {
  // TPN drives t_d at 0.5 ms/s; with time_offset.clone_trend a clone 0.8 s old is shifted by t̂_d − 0.4 ms − td_ref,
  // the newest by t̂_d − td_ref; without it both by t̂_d − td_ref.
  for (const bool trend : {false, true}) {
    VioOptions o = with_process(TdMode::Tpn, TdProcess::Tpn);
    o.td.clone_trend = trend;
    o.td.clone_trend_tau_s = 0.0; // the last rate itself
    o.td.adaptive_noise = false;
    auto m = make_td_model(o);
    State s = initialised_state(*m, 1e-3);
    s.td = 0.010;
    s.t_imu_ns = 2000000000;
    m->propagate(s, 0.010 + 0.5e-3 * 0.05, 0.05); // TPN's drive over one image interval: 0.5 ms/s
    CloneState old_clone, new_clone;
    old_clone.t_imu_ns = s.t_imu_ns - 800000000;
    old_clone.td_ref = 0.0095;
    new_clone.t_imu_ns = s.t_imu_ns;
    new_clone.td_ref = s.td;
    EXPECT_NEAR(s.td_offset_at(new_clone), 0.0, 1e-12);
    EXPECT_NEAR(s.td_offset_at(old_clone), s.td - (trend ? 0.4e-3 : 0.0) - 0.0095, 1e-9) << "clone_trend " << trend;
  }
  // Smoothed (clone_trend_tau_s): after one 0.05-s interval at 0.5 ms/s a 10-s average has 0.05 / 10.05 of it.
  VioOptions o = with_process(TdMode::Tpn, TdProcess::Tpn);
  o.td.clone_trend = true;
  o.td.clone_trend_tau_s = 10.0;
  o.td.adaptive_noise = false;
  auto m = make_td_model(o);
  State st = initialised_state(*m, 1e-3);
  st.td = 0.010;
  m->propagate(st, 0.010 + 0.5e-3 * 0.05, 0.05);
  EXPECT_NEAR(st.td_rate, 0.5e-3 * 0.05 / 10.05, 1e-12);
  // The drift state's rate is a state variable: its rows would need a rate column, so no trend is applied.
  auto d = make_td_model(with_process(TdMode::Sir, TdProcess::Drift));
  State s = initialised_state(*d, 1e-3);
  s.td_rate = 0.5e-3;
  CloneState c;
  c.t_imu_ns = s.t_imu_ns - 800000000;
  c.td_ref = s.td;
  EXPECT_NEAR(s.td_offset_at(c), 0.0, 1e-12);
}

TEST(TdModels, TpnSaysWhenItStartsPredictingAndWhenItsRateIsAtTheBound) {
  // docs/ton.md "How long TPN takes to learn": no labels while σ(t_d) is above ton.tpn_start_sigma_s, then 5 labels of
  // 10 images before the first prediction; until then t_d does not move between images. A 3 ms/s ramp asks for three
  // times time_offset.rate_max, so the propagations after the first prediction sit at the bound.
  VioOptions o = with_process(TdMode::Tpn, TdProcess::Auto);
  o.ton.tpn_label_images = 10;
  o.ton.tpn.min_labels = 5;
  o.td.adaptive_noise = false;
  auto m = make_td_model(o);
  State s = initialised_state(*m, 2e-3);
  const int64_t t0 = 1'000'000'000, step = 50'000'000;
  long propagations = 0, clamped_before = -1;
  for (int k = 0; k < 300; ++k) { // image k + 1
    if (k > 0) {
      const double td_end = m->td_at_image(s, t0 + k * step, t0 + (k - 1) * step);
      if (k < 70)
        EXPECT_EQ(td_end, s.td) << "image " << k + 1 << ": no prediction yet, t_d must not move";
      m->propagate(s, td_end, 0.05);
      ++propagations;
    }
    const bool converging = k < 20 || k == 200; // σ 2 ms (above the 1 ms bound) for 20 images, and once at 200
    s.P(s.td_index, s.td_index) = converging ? 4e-6 : 1e-8;
    s.td = 0.01 + 3e-3 * 0.05 * k; // the filter's estimate after image k + 1
    m->after_image(s, t0 + k * step);
    if (k + 1 == 70)
      clamped_before = m->stats().rate_clamped;
  }
  const TdModelStats &st = m->stats();
  EXPECT_EQ(st.tpn_first_label_image, 21);
  EXPECT_EQ(st.tpn_first_prediction_image, 70);
  EXPECT_EQ(st.tpn_label_restarts, 1);
  EXPECT_EQ(st.propagations, propagations);
  EXPECT_EQ(clamped_before, 0);
  EXPECT_GT(st.rate_clamped, 150) << "a 3 ms/s ramp against a 1 ms/s bound";
  const std::string line = describe_tpn_learning(st, o.ton.tpn.td_rate_max);
  EXPECT_NE(line.find("labels from image 21, first prediction after image 70"), std::string::npos) << line;
  EXPECT_EQ(describe_tpn_learning(make_td_model(with_process(TdMode::Drift, TdProcess::Auto))->stats(), 1e-3), "");
}
