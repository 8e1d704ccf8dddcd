// SLAM landmarks in a stereo rig (issue 40): every camera that sees a landmark in the newest image updates it. A
// further camera's row (its own extrinsics, its own offset Δ where the rig has one) against finite differences in both
// t_d observation modes, and a landmark updated by both cameras staying consistent over Monte-Carlo trials while its
// covariance shrinks below what cam0 alone gives.
#include "fd_check.h"
#include "ov_msckf_ton/update/updater_slam.h"
#include "update_test_util.h"

#include <gtest/gtest.h>

using namespace updtest;

// Camera 1's landmark row w.r.t. the newest clone, the landmark, t_d and cam1's own Δ: r = z − h, so H = −∂r/∂x.
TEST(StereoSlamJacobians, FurtherCameraRowMatchesFiniteDifferences) {
  for (const TdObservation td_obs : {TdObservation::StateRelevant, TdObservation::ImagePlane}) {
    Cam1Case rig;
    const Scene &sc = rig.sc;
    State &s = rig.s;
    const size_t id = rig.id;
    const ovton::core::CameraCalib &cal1 = rig.cal1;
    const ovton::core::Feature &f = *rig.db.get(id);
    ASSERT_EQ(f.more.size(), 1u);
    const ovton::core::Feature &track = f.more[0];
    LandmarkState l;
    l.id = id;
    l.p_W = l.p_fej = sc.points[id] + Eigen::Vector3d(0.02, 0.01, -0.03);
    l.index = s.add_variable(Eigen::Matrix3d::Identity() * 1e-4);
    s.landmarks[id] = l;
    CloneState &c = s.clones.rbegin()->second;
    c.has_fej = false; // Jacobians at the current estimate, so that differences of the residual match them
    const UpdaterMSCKF msckf(sc.calib, {}, {cal1});
    const UpdaterSLAM slam(sc.calib, UpdaterSlamOptions(), msckf);
    const VelocityProvider eq2;
    const size_t k = track.obs.size() - 1;
    LandmarkLinearization lin;
    ASSERT_TRUE(slam.linearize(msckf.camera_view(s, 1), s, s.landmarks.at(id), c, track, k, td_obs, eq2, lin));
    EXPECT_EQ(lin.td_column, td_obs == TdObservation::ImagePlane);
    ASSERT_EQ(lin.delta_index, s.cam_td[0].index);
    const auto residual = [&](const Eigen::Matrix<double, 11, 1> &d) {
      State si = s;
      CloneState &cc = si.clones.rbegin()->second;
      cc.R = so3_exp(d.segment<3>(0)) * cc.R;
      cc.p += d.segment<3>(3);
      LandmarkState &ll = si.landmarks.at(id);
      ll.p_W += d.segment<3>(6);
      ll.p_fej = ll.p_W;
      si.td += d(9);
      si.cam_td[0].delta += d(10);
      LandmarkLinearization out;
      EXPECT_TRUE(slam.linearize(msckf.camera_view(si, 1), si, ll, cc, track, k, td_obs, eq2, out));
      return out.r;
    };
    Eigen::Matrix<double, 2, 11> H;
    H << lin.H_clone, lin.H_f, lin.H_td, lin.H_delta;
    const Eigen::MatrixXd H_fd = -ovtest::numeric_jacobian(residual, Eigen::Matrix<double, 11, 1>::Zero().eval(), 1e-6);
    EXPECT_LT((H - H_fd).cwiseAbs().maxCoeff(), 1e-5 * H.cwiseAbs().maxCoeff()) << "analytic\n"
                                                                                << H << "\nnumeric\n"
                                                                                << H_fd;
  }
}

namespace {

struct LandmarkTrials {
  double nees = 0.0;         ///< mean landmark NEES over the trials
  double sigma_m = 0.0;      ///< mean of the landmark's final position sigma (sqrt of the covariance's trace)
  double rows_per_image = 0; ///< SLAM observations used per update
  int trials = 0;
};

/// Monte-Carlo trials of one landmark seen by `cameras` cameras in 14 images at the true clones, 1 px noise in each:
/// initialised from the first 5 images, updated by each later one.
LandmarkTrials landmark_trials(int cameras) {
  const Scene sc = make_scene(14, 1, 1.0, 0.0, 4);
  EXPECT_EQ(sc.points.size(), 1u);
  const ovton::core::CameraCalib cal1 = euroc_cam1();
  const ovton::core::CameraModel cam1(cal1);
  UpdaterMSCKFOptions mo;
  mo.sigma_px = 1.0;
  mo.chi2_multiplier = 100; // the covariance is tested here, not the gate
  UpdaterSlamOptions so;
  so.chi2_multiplier = 100;
  so.further_cameras = true;
  const UpdaterMSCKF msckf(sc.calib, mo,
                           cameras == 2 ? std::vector<ovton::core::CameraCalib>{cal1}
                                        : std::vector<ovton::core::CameraCalib>{});
  UpdaterSLAM slam(sc.calib, so, msckf);
  std::mt19937 rng(17);
  std::normal_distribution<double> n(0.0, 1.0);
  LandmarkTrials out;
  long rows = 0, updates = 0;
  const int init = 5;
  for (int trial = 0; trial < 200; ++trial) {
    State s = make_state(sc, 0.0, 1e-6, 1e-6, 1e-6); // the clones are the truth: only the pixels are uncertain
    ovton::core::FeatureDatabase db;
    SlamStats st;
    for (size_t i = 0; i < sc.stamps.size(); ++i) {
      const int64_t t = sc.stamps[i];
      const Pose P = sc.pose_at(sc.t_of(t));
      Eigen::Vector2d xy;
      EXPECT_TRUE(sc.project(P, sc.points[0], xy));
      const Eigen::Vector2d uv0 = sc.cam.distort(xy) + Eigen::Vector2d(n(rng), n(rng));
      db.add_observation(0, t, uv0, sc.cam.undistort(uv0));
      if (cameras == 2) {
        EXPECT_TRUE(project_in_clone(P.R, P.p, cal1.T_BC.topLeftCorner<3, 3>(), cal1.T_BC.topRightCorner<3, 1>(),
                                     sc.points[0], xy));
        const Eigen::Vector2d uv1 = cam1.distort(xy) + Eigen::Vector2d(n(rng), n(rng));
        db.add_observation(0, t, uv1, cam1.undistort(uv1), 1);
      }
      if (static_cast<int>(i) + 1 == init) {
        slam.initialize(s, {db.get(0)}, t, TdObservation::None, VelocityProvider(), st);
        if (st.initialised != 1)
          break;
      } else if (static_cast<int>(i) >= init) {
        std::vector<size_t> drop;
        const int before = st.updated;
        slam.update(s, db, t, TdObservation::None, VelocityProvider(), st, drop);
        EXPECT_TRUE(drop.empty());
        rows += st.updated - before;
        ++updates;
      }
    }
    if (!s.landmarks.count(0))
      continue;
    const LandmarkState &l = s.landmarks.at(0);
    const Eigen::Vector3d err = sc.points[0] - l.p_W;
    const Eigen::Matrix3d P = s.P.block<3, 3>(l.index, l.index);
    out.nees += err.dot(P.ldlt().solve(err));
    out.sigma_m += std::sqrt(P.trace());
    ++out.trials;
  }
  out.nees /= std::max(out.trials, 1);
  out.sigma_m /= std::max(out.trials, 1);
  out.rows_per_image = static_cast<double>(rows) / static_cast<double>(std::max(updates, 1L));
  return out;
}

} // namespace

// Both cameras' observations update the landmark: two rows per image, a consistent landmark (3-dof NEES near 3 over
// 200 trials; a row taken with the wrong camera's extrinsics or noise would bias or overstate it) and a smaller
// covariance than with cam0's rows alone.
TEST(StereoSlamUpdate, LandmarkSeenByBothCamerasIsConsistentAndBetterDetermined) {
  const LandmarkTrials mono = landmark_trials(1);
  const LandmarkTrials stereo = landmark_trials(2);
  std::cout << "mono: NEES " << mono.nees << ", sigma " << mono.sigma_m * 1e3 << " mm, rows per image "
            << mono.rows_per_image << "; stereo: NEES " << stereo.nees << ", sigma " << stereo.sigma_m * 1e3
            << " mm, rows per image " << stereo.rows_per_image << " (" << stereo.trials << " trials)\n";
  ASSERT_GT(mono.trials, 180);
  ASSERT_GT(stereo.trials, 180);
  EXPECT_DOUBLE_EQ(mono.rows_per_image, 1.0);
  EXPECT_DOUBLE_EQ(stereo.rows_per_image, 2.0);
  // 200 trials of a 3-dof NEES: the mean's standard deviation is sqrt(6/200) = 0.17.
  EXPECT_GT(stereo.nees, 2.4);
  EXPECT_LT(stereo.nees, 3.6);
  EXPECT_LT(stereo.sigma_m, 0.8 * mono.sigma_m);
}
