// Stereo rigs: the readers' further cameras (EuRoC cam1, Kalibr T_cn_cnm1, --cameras), the left-right matching with
// its epipolar check, the MSCKF measurement of a second camera against finite differences, and whole runs: the real
// micro folder in stereo, and a rendered stereo flight whose APE is below the same render's mono run.
#include "estimator_test_util.h"
#include "fd_check.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_io.h"
#include "ov_core/track/track_stereo.h"
#include "ov_core/types/errors.h"
#include "ov_eval/metrics.h"
#include "ov_sim/euroc_calib.h"
#include "sim_fixture.h"
#include "test_util.h"
#include "update_test_util.h"

#include <fstream>
#include <gtest/gtest.h>

using namespace updtest;

namespace {

std::string micro() {
  return ovtest::shared_data() + "/euroc_v1_01_micro";
}

} // namespace

TEST(StereoIo, EurocFolderHasCam1AndSelectionKeepsWhatIsAsked) {
  OVTEST_REQUIRE_SHARED_DATA();
  ovton::core::Dataset d = ovton::core::load_dataset(micro());
  ASSERT_EQ(d.num_cameras(), 2u);
  // cam1/data.csv of the cut lists four frames beyond its images: they are left out, not refused.
  EXPECT_EQ(d.more_cameras[0].images.size(), d.images.size());
  EXPECT_EQ(d.more_cameras[0].images.front().t_cam_ns, d.images.front().t_cam_ns);
  const Eigen::Vector3d baseline =
      d.more_cameras[0].cam.T_BC.topRightCorner<3, 1>() - d.cam.T_BC.topRightCorner<3, 1>();
  EXPECT_NEAR(baseline.norm(), 0.110, 0.002); // the VI-Sensor's 11 cm
  ovton::core::Dataset swapped = d;
  ovton::core::select_cameras(swapped, {1, 0});
  EXPECT_TRUE(swapped.cam.T_BC.isApprox(d.more_cameras[0].cam.T_BC));
  ovton::core::select_cameras(d, ovton::core::parse_camera_list("0"));
  EXPECT_EQ(d.num_cameras(), 1u);
  EXPECT_THROW(ovton::core::select_cameras(d, {1}), ovton::core::UsageError);
  EXPECT_THROW(ovton::core::parse_camera_list("0,x"), ovton::core::UsageError);
  EXPECT_THROW(ovton::core::parse_camera_list(""), ovton::core::UsageError);
}

TEST(StereoIo, KalibrChainTakesCam1FromTcnCnm1) {
  ovtest::TempDir dir;
  const std::string file = dir / "camchain-imucam.yaml";
  std::ofstream(file) << "cam0:\n  T_cam_imu:\n  - [0, 1, 0, 0.1]\n  - [-1, 0, 0, 0.0]\n  - [0, 0, 1, 0.02]\n"
                         "  - [0, 0, 0, 1]\n  camera_model: pinhole\n  distortion_coeffs: [0, 0, 0, 0]\n"
                         "  distortion_model: radtan\n  intrinsics: [450, 450, 376, 240]\n  resolution: [752, 480]\n"
                         "cam1:\n  T_cn_cnm1:\n  - [1, 0, 0, -0.11]\n  - [0, 1, 0, 0]\n  - [0, 0, 1, 0]\n"
                         "  - [0, 0, 0, 1]\n  camera_model: pinhole\n  distortion_coeffs: [0, 0, 0, 0]\n"
                         "  distortion_model: radtan\n  intrinsics: [451, 451, 370, 241]\n  resolution: [752, 480]\n";
  const std::vector<ovton::core::KalibrCamera> rig = ovton::core::load_kalibr_rig(file);
  ASSERT_EQ(rig.size(), 2u);
  Eigen::Matrix4d T_c1_c0 = Eigen::Matrix4d::Identity();
  T_c1_c0(0, 3) = -0.11;
  EXPECT_TRUE(rig[1].cam.T_BC.isApprox(rig[0].cam.T_BC * T_c1_c0.inverse(), 1e-12));
  // cam1 sits 11 cm along cam0's x axis: p_B(cam1 origin) = T_BC0 · (0.11, 0, 0).
  const Eigen::Vector3d o1 =
      rig[0].cam.T_BC.topLeftCorner<3, 3>() * Eigen::Vector3d(0.11, 0, 0) + rig[0].cam.T_BC.topRightCorner<3, 1>();
  const Eigen::Vector3d p1 = rig[1].cam.T_BC.topRightCorner<3, 1>();
  EXPECT_TRUE(p1.isApprox(o1, 1e-12));
}

TEST(StereoTrack, EpipolarDistanceIsZeroOnTheLineAndGrowsOffIt) {
  const Eigen::Matrix3d R = so3_exp(Eigen::Vector3d(0.01, -0.02, 0.005));
  const Eigen::Vector3d t(-0.11, 0.001, 0.002);
  const Eigen::Vector3d p0(0.3, -0.2, 4.0);
  const Eigen::Vector3d p1 = R * p0 + t;
  const Eigen::Vector2d x0 = p0.head<2>() / p0.z(), x1 = p1.head<2>() / p1.z();
  EXPECT_LT(ovton::core::epipolar_distance(R, t, x0, x1), 1e-12);
  EXPECT_NEAR(ovton::core::epipolar_distance(R, t, x0, x1 + Eigen::Vector2d(0, 0.01)), 0.01, 1e-3);
}

// Real VI-Sensor frames: the left image's features are found in the right one on their epipolar lines; the right
// image moved by 6 rows (a rig whose calibration is off by that much) loses almost all of them.
TEST(StereoTrack, MatchesRealLeftRightFramesOnEpipolarLines) {
  OVTEST_REQUIRE_SHARED_DATA();
  const ovton::core::Dataset d = ovton::core::load_dataset(micro());
  const ovton::core::CameraModel c0(d.cam), c1(d.more_cameras[0].cam);
  const cv::Mat left = ovton::core::load_gray_image(d.images[10], d.cam.width, d.cam.height);
  const cv::Mat right = ovton::core::load_gray_image(d.more_cameras[0].images[10], d.cam.width, d.cam.height);
  ovton::core::TrackKLT t0(c0);
  ovton::core::TrackSecondary t1(c0, c1);
  const auto &prim = t0.track(d.images[10].t_cam_ns, left);
  const auto &sec = t1.track(d.images[10].t_cam_ns, right, t0);
  ASSERT_GT(prim.size(), 100u);
  EXPECT_GT(sec.size(), prim.size() / 2) << "matched " << sec.size() << " of " << prim.size();
  cv::Mat shifted = cv::Mat::zeros(right.size(), right.type());
  right.rowRange(0, right.rows - 6).copyTo(shifted.rowRange(6, right.rows));
  ovton::core::TrackKLT u0(c0);
  ovton::core::TrackSecondary u1(c0, c1);
  u0.track(d.images[10].t_cam_ns, left);
  const auto &bad = u1.track(d.images[10].t_cam_ns, shifted, u0);
  EXPECT_LT(bad.size(), sec.size() / 5) << "off-line matches kept: " << bad.size();
}

// A second camera's rows: each observation its own six clone columns (repeated for a clone both cameras see); merged,
// they are the derivatives of the stacked residual with respect to each state index.
TEST(StereoJacobians, SecondCameraRowsMatchFiniteDifferences) {
  const Scene sc = make_scene(5, 5, 2.0, 0.0, 21);
  ASSERT_EQ(sc.points.size(), 5u);
  State s = make_state(sc, 0.0, 0.01, 0.02, 0.02);
  s.td = 0.004;
  ovton::core::FeatureDatabase db;
  observe(sc, db, 0.0, 1);
  const size_t id = 3;
  const ovton::core::CameraCalib cal1 = add_cam1_track(sc, db, id, 0.0);
  const ovton::core::Feature &f = *db.get(id);
  ASSERT_EQ(f.more.size(), 1u);
  UpdaterMSCKF up(sc.calib, {}, {cal1});
  const Eigen::Vector3d p_f = sc.points[id] + Eigen::Vector3d(0.02, 0.01, -0.03);
  const VelocityProvider vp;
  FeatureLinearization lin;
  // Image-plane mode: every row of both cameras but the tracks' first has a velocity; with FVON-less eq. 2 the first
  // observations have none, so no t_d column — the geometry is what is checked here.
  ASSERT_TRUE(up.linearize(s, f, p_f, TdObservation::StateRelevant, vp, lin));
  const int m = static_cast<int>(sc.stamps.size());
  ASSERT_EQ(lin.r.size(), 4 * m);
  EXPECT_EQ(lin.obs[lin.anchor].cam, 0);
  EXPECT_EQ(lin.obs[lin.anchor].clone->t_cam_ns, sc.stamps.back());
  UpdaterMSCKF::merge_repeated_columns(lin);
  ASSERT_EQ(static_cast<int>(lin.cols.size()), 6 * m);
  expect_linearization_matches_fd(up, s, f, p_f, TdObservation::StateRelevant, vp, lin);
  // At the true point the second camera's rows are zero: its extrinsics are the ones used.
  FeatureLinearization at_truth;
  ASSERT_TRUE(up.linearize(s, f, sc.points[id], TdObservation::StateRelevant, vp, at_truth));
  EXPECT_LT(at_truth.r.tail(2 * m).norm(), 1e-6);
}

// The real micro folder (vehicle still on the ground) in stereo: it initialises and stays where it is.
TEST(StereoRun, RealMicroFolderInitialisesAndStaysStill) {
  OVTEST_REQUIRE_SHARED_DATA();
  const ovton::core::Dataset d = ovton::core::load_dataset(micro());
  ovton::msckf::VioOptions opt =
      ovton::msckf::load_vio_options(OVTON_SOURCE_DIR "/config/euroc_mav/estimator_config.yaml");
  opt.td.mode = ovton::msckf::TdMode::Sr;
  ASSERT_EQ(ovton::setup_for(d, opt).more_cameras.size(), 1u);
  const ovtest::EstimatorRun r = ovtest::run_estimator(d, opt);
  ASSERT_GT(r.traj.size(), 30u);
  for (const auto &s : r.traj)
    EXPECT_LT((s.p - r.traj.front().p).norm(), 0.02);
}

// A rendered stereo flight: the same render run with both cameras beats cam0 alone.
TEST(StereoRun, StereoRenderHasLowerApeThanMono) {
  ovtest::TempDir dir;
  ovton::sim::SimOptions so;
  so.out_dir = dir.str();
  so.duration_s = 8.0;
  so.seed = 3;
  so.cameras = 2;
  ovton::sim::write_simulation(so);
  const ovton::core::Dataset d = ovton::core::load_dataset(so.out_dir);
  ASSERT_EQ(d.num_cameras(), 2u);
  ovton::msckf::VioOptions opt = ovtest::gt_run_options(ovton::msckf::TdMode::Sr, 1.0);
  double ape[2];
  for (int cams = 1; cams <= 2; ++cams) {
    opt.rig.max_cameras = cams;
    const ovtest::EstimatorRun r = ovtest::run_estimator(d, opt);
    const ovton::eval::EvalResult e = ovton::eval::evaluate(r.traj, d.groundtruth, d.td_truth, {});
    ape[cams - 1] = e.ape_rmse_m;
  }
  std::cout << "APE mono " << ape[0] << " m, stereo " << ape[1] << " m\n";
  EXPECT_LT(ape[1], ape[0]);
}
