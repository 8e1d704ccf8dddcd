// A time offset per camera (time_offset.per_camera, issue 40): a further camera's rows carry its own Δ (its t_d is
// cam0's plus Δ) checked against finite differences in both t_d observation modes, and stereo renders whose cam1 runs
// on a clock of its own (constant and drifting): each camera's t_d is recovered with the option, and the rig's one
// shared t_d cannot fit both cameras without it.
#include "estimator_test_util.h"
#include "fd_check.h"
#include "ov_core/io/dataset.h"
#include "ov_sim/euroc_calib.h"
#include "sim_fixture.h"
#include "test_util.h"
#include "update_test_util.h"

#include <gtest/gtest.h>

using namespace updtest;

// Camera 1's rows w.r.t. its own Δ (and everything else) against central differences, in the clone-time mode (sr:
// cam1's image is Δ after the clone) and the image-plane mode (sir: its shift is V·(t_d − td_ref) + V·Δ).
TEST(StereoTdJacobians, OwnOffsetColumnMatchesFiniteDifferences) {
  for (const TdObservation td_obs : {TdObservation::StateRelevant, TdObservation::ImagePlane}) {
    Cam1Case rig;
    const Scene &sc = rig.sc;
    const State &s = rig.s;
    const size_t id = rig.id;
    const ovton::core::Feature &f = *rig.db.get(id);
    const ovton::core::CameraCalib &cal1 = rig.cal1;
    UpdaterMSCKF up(sc.calib, {}, {cal1});
    const Eigen::Vector3d p_f = sc.points[id] + Eigen::Vector3d(0.02, 0.01, -0.03);
    // The next observation's velocity for the first ones: every cam0 row then carries t_d in the image-plane mode.
    const VelocityProvider base;
    const NextForFirstVelocityProvider vp(base);
    FeatureLinearization lin;
    ASSERT_TRUE(up.linearize(s, f, p_f, td_obs, vp, lin));
    const int m = static_cast<int>(sc.stamps.size());
    // cam1's first observation has no eq. 2 velocity: with its own Δ it cannot say where it was, so it is left out.
    ASSERT_EQ(static_cast<int>(lin.obs.size()), 2 * m - 1);
    const auto delta_col = std::find(lin.cols.begin(), lin.cols.end(), s.cam_td[0].index);
    ASSERT_NE(delta_col, lin.cols.end());
    const Eigen::Index j = delta_col - lin.cols.begin();
    for (int k = 0; k < static_cast<int>(lin.obs.size()); ++k) {
      const bool zero = lin.H_x.block(2 * k, j, 2, 1).isZero();
      EXPECT_EQ(zero, lin.obs[k].cam == 0) << "row block " << k;
    }
    EXPECT_EQ(std::count(lin.cols.begin(), lin.cols.end(), s.td_index), td_obs == TdObservation::ImagePlane ? 1 : 0);
    UpdaterMSCKF::merge_repeated_columns(lin);
    expect_linearization_matches_fd(up, s, f, p_f, td_obs, vp, lin);
  }
}

namespace {

/// The largest error of each camera's t_d over the rows 10 s and more after the first [s]: cam0's t_d, and cam1's
/// (its own column with per_camera, the rig's t_d without).
std::array<double, 2> td_errors_after_10s(const ovton::core::Dataset &d,
                                          const std::vector<ovton::core::StateSample> &t) {
  std::array<double, 2> worst{0.0, 0.0};
  for (const auto &s : t) {
    if (s.t_ns - t.front().t_ns < ovton::core::s_to_ns(10.0))
      continue;
    const int64_t t_cam = s.t_ns - ovton::core::s_to_ns(s.td_s);
    const double td1 = s.cam_td_s.empty() ? s.td_s : s.cam_td_s[0];
    worst[0] = std::max(worst[0], std::abs(s.td_s - d.td_truth_at(t_cam)));
    worst[1] = std::max(worst[1], std::abs(td1 - ovton::core::interpolate_td(d.more_cameras[0].td_truth, t_cam)));
  }
  return worst;
}

void expect_each_camera_recovered(const ovton::core::Dataset &d, bool rate) {
  ovton::msckf::VioOptions opt = ovtest::gt_run_options(ovton::msckf::TdMode::Sr, 1.0);
  opt.td.per_camera_rate = rate;
  std::array<double, 2> err[2];
  for (int per_camera = 0; per_camera <= 1; ++per_camera) {
    opt.td.per_camera = per_camera == 1;
    const ovtest::EstimatorRun r = ovtest::run_estimator(d, opt);
    ASSERT_GT(r.traj.size(), 220u);
    ASSERT_EQ(r.traj.back().cam_td_s.size(), per_camera == 1 ? 1u : 0u);
    err[per_camera] = td_errors_after_10s(d, r.traj);
    std::cout << (per_camera ? "per camera" : "shared") << ": worst t_d error after 10 s, cam0 "
              << err[per_camera][0] * 1e3 << " ms, cam1 " << err[per_camera][1] * 1e3 << " ms\n";
  }
  EXPECT_LT(err[1][0], 0.5e-3);
  EXPECT_LT(err[1][1], 0.5e-3);
  // One t_d for both cameras: at least one of them is off by more than the bar.
  EXPECT_GT(std::max(err[0][0], err[0][1]), 0.5e-3);
}

} // namespace

// cam0 at 10 ms, cam1 at 14 ms, both constant.
TEST(StereoTdRun, EachCameraOffsetRecoveredWhenCam1HasItsOwn) {
  ovtest::TempDir dir;
  const ovton::core::Dataset d = ovtest::cam1_clock_render(dir.str(), 0.010, 0.014, 0.0);
  ASSERT_EQ(d.num_cameras(), 2u);
  ASSERT_FALSE(d.more_cameras[0].td_truth.empty());
  expect_each_camera_recovered(d, false);
}

// cam0 at 10 ms, cam1 from 14 ms drifting by 0.1 ms/s on its own clock: cam1's offset with a rate of its own.
TEST(StereoTdRun, DriftingCam1OffsetRecovered) {
  ovtest::TempDir dir;
  const ovton::core::Dataset d = ovtest::cam1_clock_render(dir.str(), 0.010, 0.014, 1e-4);
  expect_each_camera_recovered(d, true);
}
