// diagnose per camera (issue 40): a rig's further cameras write residual logs of their own (res_cam1.csv beside
// res.csv), each diagnosed with that camera's calibration. A stereo render whose cam1 runs on a clock of its own, run
// with the rig's one shared t_d: the shared estimate settles between the two cameras' offsets, and each camera's log
// names the offset error of that camera, with opposite signs.
#include "diagnose_test_util.h"
#include "estimator_test_util.h"
#include "ov_core/io/residual_log_schema.h"
#include "ov_eval/diagnose.h"
#include "ov_msckf_ton/core/filter_observer.h"
#include "sim_fixture.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

TEST(ResidualLogPaths, EachCameraHasAFileOfItsOwn) {
  using ovton::core::camera_of_residual_log;
  using ovton::core::residual_log_path_of_camera;
  EXPECT_EQ(residual_log_path_of_camera("out/res.csv", 0), "out/res.csv");
  EXPECT_EQ(residual_log_path_of_camera("out/res.csv", 1), "out/res_cam1.csv");
  EXPECT_EQ(residual_log_path_of_camera("out.d/res", 2), "out.d/res_cam2");
  EXPECT_EQ(camera_of_residual_log("out/res_cam1.csv"), 1);
  EXPECT_EQ(camera_of_residual_log("out/res_cam12.csv"), 12);
  EXPECT_EQ(camera_of_residual_log("out/res.csv"), 0);
  EXPECT_EQ(camera_of_residual_log("out/res_camera.csv"), 0);
  EXPECT_EQ(camera_of_residual_log("run_cam1/res.csv"), 0);
}

namespace {

/// The mean of the filter's t_d over a log's rows [s].
double mean_td(const ovton::core::ResidualLog &log) {
  double s = 0;
  for (const auto &r : log.rows)
    s += r.td_s;
  return s / static_cast<double>(std::max<size_t>(log.rows.size(), 1));
}

ovton::eval::DiagnoseReport diagnose_camera(const ovton::core::ResidualLog &log, const ovton::core::Dataset &d,
                                            int cam) {
  ovton::eval::DiagnoseOptions o;
  o.camera = cam == 0 ? d.cam : d.more_cameras[static_cast<size_t>(cam - 1)].cam;
  o.have_camera = true;
  o.imu = d.imu;
  const ovton::eval::DiagnoseReport rep = ovton::eval::diagnose(log, o);
  std::cout << "camera " << cam << ": " << log.rows.size() << " rows\n" << ovton::eval::format_ranking(rep);
  return rep;
}

} // namespace

// cam0 at 10 ms, cam1 at 14 ms; the rig's one t_d settles between them (docs/stereo.md): cam1's log names its
// offset error, cam0's reads the opposite sign.
TEST(StereoDiagnose, EachCamerasLogNamesItsOwnOffsetError) {
  ovtest::TempDir dir;
  const ovton::core::Dataset d = ovtest::cam1_clock_render(dir / "sim", 0.010, 0.014, 0.0);
  ovton::msckf::VioOptions opt = ovtest::gt_run_options(ovton::msckf::TdMode::Sr, 1.0);
  const std::string log_file = dir / "res.csv";
  ovtest::run_estimator(d, opt, {std::make_shared<ovton::msckf::ResidualLogObserver>(log_file)});
  const std::string cam1_file = ovton::core::residual_log_path_of_camera(log_file, 1);
  ASSERT_TRUE(std::filesystem::exists(cam1_file));
  const ovton::core::ResidualLog log0 = ovton::core::load_residual_log(log_file);
  const ovton::core::ResidualLog log1 = ovton::core::load_residual_log(cam1_file);
  ASSERT_GT(log1.rows.size(), log0.rows.size() / 4);
  const double td0 = mean_td(log0), td1 = mean_td(log1);
  std::cout << "mean shared t_d over the rows: cam0's " << td0 * 1e3 << " ms, cam1's " << td1 * 1e3 << " ms\n";
  // The offset errors the logs should show: the true offsets minus the shared estimate [ms].
  const double want0 = (0.010 - td0) * 1e3, want1 = (0.014 - td1) * 1e3;
  ASSERT_LT(want0, -0.5);
  ASSERT_GT(want1, 0.5);
  // cam1's log: its offset named first, within 2.5 of its own standard errors of the mean error over the rows (the
  // estimate weights the rows by their rotation, the mean does not: the early rows, before the shared t_d moved up
  // from 10 ms, weigh more or less).
  const ovton::eval::DiagnoseReport rep1 = diagnose_camera(log1, d, 1);
  ASSERT_FALSE(rep1.candidates.empty());
  const ovton::eval::CandidateResult &top1 = ovtest::top(rep1);
  EXPECT_EQ(top1.key, "td_const");
  EXPECT_TRUE(top1.explained);
  ASSERT_FALSE(top1.estimates.empty());
  EXPECT_NEAR(top1.estimates[0].value, want1, 2.5 * top1.estimates[0].stderr_);
  // cam0's: the same candidate reads the opposite sign (its poses absorb part of it; with cam0's rows driving the
  // shared estimate it is not significant here).
  const ovton::eval::DiagnoseReport rep0 = diagnose_camera(log0, d, 0);
  const auto td0_const = std::find_if(rep0.candidates.begin(), rep0.candidates.end(),
                                      [](const ovton::eval::CandidateResult &c) { return c.key == "td_const"; });
  ASSERT_NE(td0_const, rep0.candidates.end());
  EXPECT_LT(ovtest::estimate(*td0_const, "offset error δt"), 0.0);
}
