// The velocity log (ov_core/io/velocity_log.h) and its scoring against the truth (ov_eval/velocity_truth.h).
#include "estimator_test_util.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/velocity_log.h"
#include "ov_eval/velocity_truth.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_sim/simulator.h"
#include "sim_fixture.h"
#include "test_util.h"

#include <cmath>

using namespace ovton::msckf;

TEST(VelocityLog, RoundTripKeepsMissingVelocitiesMissing) {
  ovtest::TempDir tmp;
  ovton::core::VelocityLogRow a;
  a.t_cam_ns = 1403715285262142976;
  a.feature_id = 42;
  a.track_length = 5;
  a.u_px = 12.5;
  a.next_x = -31.25;
  a.next_y = 7.0;
  a.its_x = 1.5;
  a.its_y = 2.5;
  a.used_source = 2;
  a.fvon_source = 2;
  a.focal_px = 457.975;
  ovton::core::VelocityLogRow b = a;
  b.obs_index = 1;
  b.eq2_x = 3.0;
  b.eq2_y = 4.0;
  b.gated = 1;
  {
    ovton::core::VelocityLogWriter w(tmp / "v.csv");
    w.write({a, b});
  }
  const auto rows = ovton::core::read_velocity_log(tmp / "v.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].t_cam_ns, a.t_cam_ns);
  EXPECT_EQ(rows[0].feature_id, 42u);
  EXPECT_TRUE(std::isnan(rows[0].eq2_x));
  EXPECT_TRUE(std::isnan(rows[0].f2f_y));
  EXPECT_DOUBLE_EQ(rows[0].next_x, -31.25);
  EXPECT_EQ(rows[0].fvon_source, 2);
  EXPECT_DOUBLE_EQ(rows[1].eq2_y, 4.0);
  EXPECT_EQ(rows[1].gated, 1);
  // A truncated row names the file and line.
  ovtest::write_text(tmp / "bad.csv", ovton::core::VelocityLogWriter::header() + "\n1,2,3\n");
  try {
    ovton::core::read_velocity_log(tmp / "bad.csv");
    FAIL() << "short row accepted";
  } catch (const ovton::core::DataError &e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_NE(std::string(e.what()).find("bad.csv"), std::string::npos);
  }
}

TEST(VelocityTruth, NoiseFreeTracksScoreNearZeroAndNetworksAreScored) {
  // A noise-free feature-level flight: eq. 2 and `next` differ from the true instantaneous velocity only by half a
  // frame of image acceleration; FVON (mode fvon) predicts with both networks for every new feature.
  ovtest::TempDir tmp;
  const ovton::core::Dataset data = ovtest::feature_flight(tmp / "sim", 6.0, 3, 0.0);
  VioOptions opt = ovtest::gt_run_options(TdMode::Fvon, VioOptions().update.msckf.sigma_px);
  opt.ton.fvon.its.train.max_epochs = 100;
  opt.ton.fvon.f2f.train.max_epochs = 150;
  ovtest::run_estimator(data, opt, {std::make_shared<ovton::msckf::VelocityLogObserver>(tmp / "vel.csv")});
  const auto rows = ovton::core::read_velocity_log(tmp / "vel.csv");
  ASSERT_GT(rows.size(), 1000u);
  const ovton::eval::VelocityEvalResult r = ovton::eval::evaluate_velocities(rows, data);
  std::cout << ovton::eval::velocity_table(r);
  EXPECT_GT(r.features_scored, r.features / 2);
  const auto score = [&](const std::string &obs, const std::string &rule) {
    for (const auto &s : r.scores)
      if (s.observations == obs && s.rule == rule)
        return s;
    ADD_FAILURE() << "no score for " << obs << " " << rule;
    return ovton::eval::VelocityScore{};
  };
  const auto eq2 = score("tracked", "eq2"), next = score("first", "next");
  EXPECT_GT(eq2.count, 1000);
  EXPECT_GT(next.count, 100);
  // Half a frame of the built-in flight's image acceleration: a few px/s against speeds of hundreds.
  EXPECT_LT(eq2.rms_px_s, 0.05 * eq2.true_rms_px_s);
  EXPECT_LT(next.rms_px_s, 0.1 * next.true_rms_px_s);
  EXPECT_GT(score("first", "its_fvon").count, 0);
  EXPECT_GT(score("first", "f2f_fvon").count, 0);
  // A scored velocity that is wrong shows: zero velocity is off by the whole speed.
  std::vector<ovton::core::VelocityLogRow> zeroed = rows;
  for (auto &row : zeroed)
    if (std::isfinite(row.eq2_x))
      row.eq2_x = row.eq2_y = 0.0;
  const auto z = ovton::eval::evaluate_velocities(zeroed, data);
  for (const auto &s : z.scores)
    if (s.rule == "eq2") {
      EXPECT_NEAR(s.rms_px_s, s.true_rms_px_s, 1e-9);
    }
}
