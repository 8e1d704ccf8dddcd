// Estimator configuration, static initialisation, and whole runs of the VioManager.
#include "ov_core/io/dataset.h"
#include "ov_core/io/replay.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/core/static_init.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_msckf_ton/core/vio_options.h"
#include "test_util.h"

#include <sstream>

using namespace ov_msckf_ton;

TEST(VioOptions, ShippedConfigLoadsAndUnknownKeysFail) {
  std::ostringstream printed;
  const VioOptions o =
      load_vio_options(std::string(OVTON_SOURCE_DIR) + "/config/euroc_mav/estimator_config.yaml", &printed);
  EXPECT_EQ(o.td_mode, TdMode::Sr);
  EXPECT_EQ(o.max_clones, 20);
  EXPECT_NE(printed.str().find("max_clones: 20"), std::string::npos);
  ovtest::TempDir tmp;
  ovtest::write_text(tmp / "bad.yaml", "max_clones: 11\nmax_clone: 5\n");
  try {
    load_vio_options(tmp / "bad.yaml");
    FAIL() << "unknown key accepted";
  } catch (const ov_core::DataError &e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_NE(std::string(e.what()).find("max_clone"), std::string::npos);
  }
  ovtest::write_text(tmp / "bad2.yaml", "td_mode: fast\n");
  EXPECT_THROW(load_vio_options(tmp / "bad2.yaml"), ov_core::UsageError);
  ovtest::write_text(tmp / "bad3.yaml", "sigma_px: [1, 2]\n");
  EXPECT_THROW(load_vio_options(tmp / "bad3.yaml"), ov_core::DataError);
}

TEST(StaticInit, RealEurocStillStartMatchesGroundTruth) {
  OVTEST_REQUIRE_SHARED_DATA();
  const ov_core::Dataset d = ov_core::load_dataset(ovtest::shared_data() + "/euroc_v1_01_micro");
  std::deque<ov_core::ImuData> imu(d.imu.begin(), d.imu.begin() + 400); // the first 2 s
  const int64_t t_end = imu.back().t_imu_ns;
  const StaticInitResult r = static_initialize(imu, t_end, 1.0, 1.0, 0.1);
  ASSERT_TRUE(r.ok) << r.why;
  // Gravity direction in the body: from the estimate and from the ground truth (yaw does not matter).
  const ov_core::StateSample &g = d.groundtruth.front();
  const Eigen::Vector3d z_est = r.R_WB.transpose() * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d z_gt = g.q_WB.toRotationMatrix().transpose() * Eigen::Vector3d::UnitZ();
  const double angle_deg = std::acos(std::min(1.0, z_est.dot(z_gt))) * 180 / M_PI;
  // The residual tilt is the accelerometer bias seen as gravity (|b_a| ~ 0.08 m/s^2 here, ~0.5 deg).
  EXPECT_LT(angle_deg, 1.0);
  EXPECT_LT((r.bg - g.bg).norm(), 0.005) << r.bg.transpose() << " vs " << g.bg.transpose();
  // Yaw convention: body x projected on the horizontal is world x.
  const Eigen::Vector3d x_W = r.R_WB * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(x_W.y(), 0.0, 1e-12);
  // A moving stretch is refused with a reason.
  std::deque<ov_core::ImuData> moving = imu;
  for (size_t i = 0; i < moving.size(); ++i)
    moving[i].am.x() += (i % 2 ? 2.0 : -2.0);
  const StaticInitResult m = static_initialize(moving, t_end, 1.0, 1.0, 0.1);
  EXPECT_FALSE(m.ok);
  EXPECT_NE(m.why.find("moving"), std::string::npos);
}

TEST(VioRun, RealEurocStillStartStaysPut) {
  OVTEST_REQUIRE_SHARED_DATA();
  const ov_core::Dataset d = ov_core::load_dataset(ovtest::shared_data() + "/euroc_v1_01_micro");
  const VioOptions opt = load_vio_options(std::string(OVTON_SOURCE_DIR) + "/config/euroc_mav/estimator_config.yaml");
  VioManager vio(opt, d.cam, d.imu_calib);
  std::vector<ov_core::StateSample> traj;
  vio.set_state_callback([&](const ov_core::StateSample &s) { traj.push_back(s); });
  ov_core::Replay(d).run(vio);
  ASSERT_TRUE(vio.initialized()) << vio.init_message();
  ASSERT_GT(traj.size(), 50u);
  double max_move = 0.0;
  for (const auto &s : traj)
    max_move = std::max(max_move, (s.p - traj.front().p).norm());
  std::cout << "[still start] " << traj.size() << " poses, largest displacement " << max_move * 100 << " cm, "
            << vio.counters().zupts << " zero-velocity updates\n";
  EXPECT_LT(max_move, 0.05);
  // Gravity from static initialisation agrees with the ground truth's tilt.
  const ov_core::StateSample &g = d.groundtruth.front();
  const Eigen::Vector3d z_est = traj.front().q_WB.toRotationMatrix().transpose() * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d z_gt = g.q_WB.toRotationMatrix().transpose() * Eigen::Vector3d::UnitZ();
  EXPECT_LT(std::acos(std::min(1.0, z_est.dot(z_gt))) * 180 / M_PI, 1.0);
}
