// Estimator configuration, static initialisation, and whole runs of the VioManager.
#include "estimator_test_util.h"
#include "ov_core/io/dataset.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/core/static_init.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_msckf_ton/core/vio_options.h"
#include "test_util.h"

#include <sstream>

using namespace ovton::msckf;

TEST(VioOptions, ShippedConfigLoadsAndUnknownKeysFail) {
  std::ostringstream printed;
  const VioOptions o =
      load_vio_options(std::string(OVTON_SOURCE_DIR) + "/config/euroc_mav/estimator_config.yaml", &printed);
  EXPECT_EQ(o.td.mode, TdMode::Drift); // real recordings: an undeclared drift is the common case (test_real_td.cpp)
  EXPECT_EQ(o.update.max_clones, 20);
  EXPECT_NE(printed.str().find("\n  update:\n"), std::string::npos) << printed.str();
  EXPECT_NE(printed.str().find("\n    max_clones: 20\n"), std::string::npos) << printed.str();
  ovtest::TempDir tmp;
  // Each bad file: the error names the file and the line of the offending key or value.
  const auto expect_error = [&](const std::string &name, const std::string &text, int line, const std::string &what) {
    ovtest::write_text(tmp / name, text);
    try {
      load_vio_options(tmp / name);
      ADD_FAILURE() << name << " accepted";
    } catch (const ovton::core::DataError &e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      if (line > 0) {
        EXPECT_EQ(e.line(), line) << e.what();
      }
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expect_error("unknown.yaml", "update:\n  max_clones: 11\n  max_clone: 5\n", 3, "update.max_clone");
  expect_error("section.yaml", "updates:\n  max_clones: 11\n", 1, "unknown section 'updates'");
  expect_error("mode.yaml", "time_offset:\n  mode: fast\n", 2, "unknown time-offset mode 'fast'");
  expect_error("kind.yaml", "update:\n  sigma_px: [1, 2]\n", 2, "must be a single value");
  expect_error("flat.yaml", "max_clones: 11\n", 1, "unknown section");
  expect_error("dup.yaml", "update:\n  sigma_px: 1\n  sigma_px: 2\n", 3, "duplicate key 'update.sigma_px'");
  expect_error("range.yaml", "imu:\n  gravity_mag: 0\n", 0, "imu.gravity_mag must be > 0");
  expect_error("enum.yaml", "time_offset:\n  first_velocity: later\n", 2, "expected none, next");
  expect_error("noise.yaml", "imu:\n  gyroscope_noise_density: -1e-4\n", 0, "imu noise densities");
  // The EuRoC config declares the ADIS16448's measured noise, which replaces the folders' datasheet values.
  EXPECT_GT(o.imu.gyroscope_noise_density, 4 * 1.6968e-4);
  EXPECT_GT(o.imu.accelerometer_noise_density, 4 * 2.0e-3);
  // MODE+PROCESS specs: the process overrides the mode's own.
  VioOptions spec;
  apply_mode_spec(parse_mode_spec("sr+random_walk"), spec);
  EXPECT_EQ(spec.td.mode, TdMode::Sr);
  EXPECT_EQ(resolve_td_process(spec.td.mode, spec.td.process), TdProcess::RandomWalk);
  EXPECT_EQ(resolve_td_process(TdMode::Ton, TdProcess::Auto), TdProcess::Tpn);
  EXPECT_EQ(resolve_td_process(TdMode::Drift, TdProcess::Auto), TdProcess::Drift);
  EXPECT_THROW(parse_mode_spec("oracle+drift"), ovton::core::UsageError);
  EXPECT_THROW(parse_mode_spec("sr+wobble"), ovton::core::UsageError);
}

TEST(StaticInit, RealEurocStillStartMatchesGroundTruth) {
  OVTEST_REQUIRE_SHARED_DATA();
  const ovton::core::Dataset d = ovton::core::load_dataset(ovtest::shared_data() + "/euroc_v1_01_micro");
  std::deque<ovton::core::ImuData> imu(d.imu.begin(), d.imu.begin() + 400); // the first 2 s
  const int64_t t_end = imu.back().t_imu_ns;
  const StaticInitResult r = static_initialize(imu, t_end, 1.0, 1.0, 0.1);
  ASSERT_TRUE(r.ok) << r.why;
  // Gravity direction in the body: from the estimate and from the ground truth (yaw does not matter).
  const ovton::core::StateSample &g = d.groundtruth.front();
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
  std::deque<ovton::core::ImuData> moving = imu;
  for (size_t i = 0; i < moving.size(); ++i)
    moving[i].am.x() += (i % 2 ? 2.0 : -2.0);
  const StaticInitResult m = static_initialize(moving, t_end, 1.0, 1.0, 0.1);
  EXPECT_FALSE(m.ok);
  EXPECT_NE(m.why.find("moving"), std::string::npos);
}

TEST(VioRun, RealEurocStillStartStaysPut) {
  OVTEST_REQUIRE_SHARED_DATA();
  const ovton::core::Dataset d = ovton::core::load_dataset(ovtest::shared_data() + "/euroc_v1_01_micro");
  VioOptions opt = load_vio_options(std::string(OVTON_SOURCE_DIR) + "/config/euroc_mav/estimator_config.yaml");
  opt.td.search.enabled = false; // still images: nothing to search
  const ovtest::EstimatorRun run = ovtest::run_estimator(d, opt);
  const std::vector<ovton::core::StateSample> &traj = run.traj;
  ASSERT_GT(traj.size(), 50u) << run.report.init_message;
  double max_move = 0.0;
  for (const auto &s : traj)
    max_move = std::max(max_move, (s.p - traj.front().p).norm());
  std::cout << "[still start] " << traj.size() << " poses, largest displacement " << max_move * 100 << " cm, "
            << run.report.counters.zupts << " zero-velocity updates\n";
  EXPECT_LT(max_move, 0.05);
  // Gravity from static initialisation agrees with the ground truth's tilt.
  const ovton::core::StateSample &g = d.groundtruth.front();
  const Eigen::Vector3d z_est = traj.front().q_WB.toRotationMatrix().transpose() * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d z_gt = g.q_WB.toRotationMatrix().transpose() * Eigen::Vector3d::UnitZ();
  EXPECT_LT(std::acos(std::min(1.0, z_est.dot(z_gt))) * 180 / M_PI, 1.0);
}
