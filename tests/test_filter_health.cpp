// FilterHealth (ov_msckf_ton/core/filter_health.h): a non-finite state, a collapsed update acceptance and a gate rate
// far beyond chance stop the run; healthy stretches and too little evidence do not. End to end: an absurd IMU reading
// after initialisation (one the reader's range check lets through) must not come out as NaN rows.
#include "ov_core/io/dataset.h"
#include "ov_core/io/replay.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/core/filter_health.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_sim/simulator.h"
#include "test_util.h"

#include <cmath>
#include <limits>

using namespace ov_msckf_ton;

namespace {

UpdateStats stats(int used, int gated, int tri) {
  UpdateStats st;
  st.features_used = used;
  st.gated_chi2 = gated;
  st.rejected_triangulation = tri;
  return st;
}

/// One update every 50 ms from t0_s for dur_s seconds; t_d and its variance from td(t) and var(t).
template <typename Td = double (*)(double), typename Var = double (*)(double)>
void feed(
    FilterHealth &h, double t0_s, double dur_s, const UpdateStats &st, Td td = [](double) { return 0.01; },
    Var var = [](double) { return 1e-8; }) {
  State s;
  s.P = Eigen::MatrixXd::Identity(s.dim(), s.dim());
  for (double t = t0_s; t < t0_s + dur_s - 1e-9; t += 0.05) {
    s.t_imu_ns = ov_core::s_to_ns(t);
    s.td = td(t);
    s.P(s.td_index, s.td_index) = var(t);
    h.on_update(s, st);
  }
}

/// The message of the EstimatorFailure `f` throws ("" when it throws none).
template <typename F> std::string failure(F f) {
  try {
    f();
  } catch (const ov_core::EstimatorFailure &e) {
    return e.what();
  }
  return "";
}

} // namespace

TEST(FilterHealth, HealthyRunsAndThinEvidencePass) {
  State s;
  FilterHealth h;
  feed(h, 0, 5, stats(20, 1, 1)); // ~90 % accepted, as measured on rendered and real EuRoC runs
  EXPECT_EQ(failure([&] { h.check(s); }), "");
  EXPECT_NEAR(h.total().acceptance(), 20.0 / 22.0, 1e-12);
  FilterHealth thin;
  feed(thin, 0, 0.1, stats(0, 10, 10)); // 40 features: too few to call it a collapse
  EXPECT_EQ(failure([&] { thin.check(s); }), "");
}

TEST(FilterHealth, CollapsedAcceptanceAndGateRateBeyondChanceFail) {
  State s;
  FilterHealth diverged; // what a filter started 150 ms off shows from its first second (docs/robustness.md)
  feed(diverged, 0, 1, stats(0, 5, 15));
  EXPECT_NE(failure([&] { diverged.check(s); }).find("diverged"), std::string::npos);
  FilterHealth gated; // triangulation fine, but most features fail the 95 % gate
  feed(gated, 0, 1, stats(8, 12, 0));
  EXPECT_NE(failure([&] { gated.check(s); }).find("chi-square gate"), std::string::npos);
  // A bad stretch that the last window_s seconds no longer hold is history, not a failure now.
  FilterHealth recovered;
  feed(recovered, 0, 1, stats(0, 5, 15));
  feed(recovered, 1, 4, stats(20, 1, 1));
  EXPECT_EQ(failure([&] { recovered.check(s); }), "");
}

TEST(FilterHealth, TdRunningAwayFromItsCovarianceFails) {
  State s;
  // The image-plane modes' fast-start divergence: 4 ms/s with sigma 0.3 ms (docs/robustness.md).
  FilterHealth runaway;
  feed(
      runaway, 0, 3, stats(20, 1, 1), [](double t) { return 0.07 + 0.004 * t; }, [](double) { return 9e-8; });
  EXPECT_NE(failure([&] { runaway.check(s); }).find("running away"), std::string::npos);
  // Converging from 40 ms off with a 10 ms prior: a large step, but paid for by the variance it gained (4 sigma).
  FilterHealth converging;
  feed(
      converging, 0, 3, stats(20, 1, 1), [](double t) { return t < 1 ? 0.05 - 0.04 * t : 0.01; },
      [](double t) { return t < 1 ? 1e-4 * (1 - t) + 1e-6 : 1e-6; });
  EXPECT_EQ(failure([&] { converging.check(s); }), "");
  // TPN may drive the mean at up to its clamp (1 ms/s): 1.5 ms/s for 2 s is 1 ms beyond it in tpn/ton, 3 ms in sr.
  VioOptions ton;
  ton.td_mode = TdMode::Ton;
  FilterHealth tpn(ton), sr(VioOptions{});
  for (FilterHealth *h : {&tpn, &sr})
    feed(
        *h, 0, 3, stats(20, 1, 1), [](double t) { return 0.01 + 0.0015 * t; }, [](double) { return 1e-8; });
  EXPECT_EQ(failure([&] { tpn.check(s); }), "");
  EXPECT_NE(failure([&] { sr.check(s); }).find("running away"), std::string::npos);
  // health_checks: false only counts.
  VioOptions off;
  off.health_checks = false;
  FilterHealth quiet(off);
  feed(quiet, 0, 1, stats(0, 5, 15));
  EXPECT_EQ(failure([&] { quiet.check(s); }), "");
}

TEST(FilterHealth, NonFiniteStateOrCovarianceFails) {
  const auto broken = [](auto edit) {
    State s;
    s.P = Eigen::MatrixXd::Identity(s.dim(), s.dim());
    edit(s);
    return failure([&] { FilterHealth().check(s); });
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(broken([](State &) {}), "");
  EXPECT_NE(broken([&](State &s) { s.imu.v(1) = nan; }).find("IMU pose or velocity"), std::string::npos);
  EXPECT_NE(broken([&](State &s) { s.td = nan; }).find("t_d"), std::string::npos);
  EXPECT_NE(broken([&](State &s) { s.P(4, 4) = std::numeric_limits<double>::infinity(); }).find("covariance"),
            std::string::npos);
  EXPECT_NE(broken([&](State &s) { s.P(2, 2) = -1; }).find("negative variance"), std::string::npos);
}

// A feature-level flight with one accelerometer reading of 4000 m/s^2 (inside the reader's range, 5000) after
// initialisation: the rows handed out are finite up to the spike, and then the run stops with EstimatorFailure.
TEST(FilterHealth, AbsurdImuReadingAfterInitialisationStopsTheRun) {
  ovtest::TempDir tmp;
  ov_sim::SimOptions o;
  o.out_dir = tmp / "sim";
  o.duration_s = 8.0;
  o.seed = 3;
  o.features_only = true;
  ov_sim::write_simulation(o);
  ov_core::Dataset data = ov_core::load_dataset(o.out_dir);
  const size_t k = data.imu.size() / 2;
  data.imu[k].am = Eigen::Vector3d(4000, -4000, 4000);

  VioOptions opt;
  opt.init_mode = InitMode::GroundTruth;
  VioManager vio(opt, data.cam, data.imu_calib);
  vio.set_groundtruth(data.groundtruth);
  std::vector<ov_core::StateSample> rows;
  vio.set_state_callback([&](const ov_core::StateSample &s) { rows.push_back(s); });
  try {
    ov_core::Replay(data).run(vio);
    FAIL() << "a run through a 4000 m/s^2 spike ended normally with " << rows.size() << " rows";
  } catch (const ov_core::EstimatorFailure &e) {
    EXPECT_GT(e.t_ns(), data.imu[k].t_imu_ns) << e.what();
  }
  ASSERT_GT(rows.size(), 10u);
  for (const auto &r : rows)
    ASSERT_TRUE(r.p.allFinite() && r.v.allFinite() && std::isfinite(r.td_s)) << "non-finite row at " << r.t_ns;
}
