// A rig's reported covariance (update.covariance_camera_correlation): cam1 finds its features by KLT from cam0's image
// at the same instant, so the two cameras' errors of one feature are correlated. The reported covariance's track
// model takes that in; monocular features are untouched.
#include "ov_msckf_ton/state/state_helper.h"
#include "ov_msckf_ton/update/updater_msckf.h"
#include "update_test_util.h"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

using namespace ovton::msckf;
using namespace updtest;

namespace {

/// Every point seen by cam0 and cam1 (euroc_cam1) in every image, pixel errors of the separable model: AR(1) ρ over
/// the images, correlation rho_cam between the cameras' errors of a point in one image, marginal sigma_px.
void observe_rig(const Scene &sc, const ovton::core::CameraCalib &cal1, ovton::core::FeatureDatabase &db,
                 double sigma_px, double rho, double rho_cam, unsigned seed) {
  const ovton::core::CameraModel cam1(cal1);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, sigma_px);
  const auto draw = [&] { return Eigen::Vector2d(n(rng), n(rng)); };
  const double s = std::sqrt(1.0 - rho * rho), sc_ = std::sqrt(1.0 - rho_cam * rho_cam);
  std::vector<Eigen::Vector2d> e0(sc.points.size()), e1(sc.points.size());
  for (size_t id = 0; id < sc.points.size(); ++id) {
    e0[id] = draw();
    e1[id] = rho_cam * e0[id] + sc_ * draw();
  }
  bool first = true;
  for (int64_t t : sc.stamps) {
    const Pose P = sc.pose_at(sc.t_of(t) + sc.td_true);
    for (size_t id = 0; id < sc.points.size(); ++id) {
      if (!first) { // both AR(1) with innovations correlated by rho_cam: stationary cross-correlation rho_cam
        const Eigen::Vector2d w0 = draw();
        e0[id] = rho * e0[id] + s * w0;
        e1[id] = rho * e1[id] + s * (rho_cam * w0 + sc_ * draw());
      }
      Eigen::Vector2d xy0, xy1;
      ASSERT_TRUE(sc.project(P, sc.points[id], xy0));
      ASSERT_TRUE(project_in_clone(P.R, P.p, cal1.T_BC.topLeftCorner<3, 3>(), cal1.T_BC.topRightCorner<3, 1>(),
                                   sc.points[id], xy1));
      const Eigen::Vector2d uv0 = sc.cam.distort(xy0) + e0[id], uv1 = cam1.distort(xy1) + e1[id];
      db.add_observation(id, t, uv0, sc.cam.undistort(uv0));
      db.add_observation(id, t, uv1, cam1.undistort(uv1), 1);
    }
    first = false;
  }
}

/// Mean NEES/dim of the clones after one stereo update over Monte-Carlo trials (the estimate the truth moved by a
/// draw from the prior): with the filter's own covariance and with the reported one (covariance_track_correlation
/// rho, covariance_camera_correlation report_cam).
struct RigMonteCarlo {
  double nees_own = 0, nees_report = 0, nees_prior = 0;
};
RigMonteCarlo rig_monte_carlo(double rho, double rho_cam, double report_cam, int trials, unsigned seed) {
  const Scene sc = make_scene(10, 20, 1.0, 0.0, 21);
  State truth = make_state(sc, 0.0, 0.001, 0.003, 0.01);
  add_common_clone_prior(truth, 0.01, 0.05);
  const int n = truth.dim();
  const Eigen::MatrixXd L = truth.P.llt().matrixL();
  const ovton::core::CameraCalib cal1 = euroc_cam1();
  UpdaterMSCKFOptions uo;
  uo.sigma_px = 1.0;
  uo.chi2_multiplier = 100.0; // no gating: the test is of the covariance, not of the gate
  uo.covariance_track_correlation = rho;
  uo.covariance_camera_correlation = report_cam;
  UpdaterMSCKF up(sc.calib, uo, {cal1});
  const VelocityProvider vp;
  std::mt19937 rng(seed);
  std::normal_distribution<double> N01;
  RigMonteCarlo mc;
  for (int k = 0; k < trials; ++k) {
    Eigen::VectorXd w(n);
    for (int i = 0; i < n; ++i)
      w(i) = N01(rng);
    const Eigen::VectorXd e0 = L * w;
    State s = truth;
    s.boxplus(-e0);
    s.start_report();
    ovton::core::FeatureDatabase db;
    observe_rig(sc, cal1, db, 1.0, rho, rho_cam, seed * 7919u + static_cast<unsigned>(k));
    up.update(s, all_features(db), TdObservation::None, vp);
    const int nc = CloneState::kSize * static_cast<int>(s.clones.size());
    Eigen::VectorXd e(nc), ep(nc);
    std::vector<int> idx;
    int j = 0;
    for (const auto &[t, c] : s.clones) {
      const CloneState &ct = truth.clones.at(t);
      e.segment<3>(j) = so3_log(ct.R * c.R.transpose());
      e.segment<3>(j + 3) = ct.p - c.p;
      ep.segment<6>(j) = e0.segment<6>(c.index);
      for (int q = 0; q < 6; ++q)
        idx.push_back(c.index + q);
      j += 6;
    }
    Eigen::MatrixXd P(nc, nc), Pr(nc, nc), P0(nc, nc);
    for (int a = 0; a < nc; ++a)
      for (int b = 0; b < nc; ++b) {
        P(a, b) = s.P(idx[a], idx[b]);
        Pr(a, b) = s.P_report(idx[a], idx[b]);
        P0(a, b) = truth.P(idx[a], idx[b]);
      }
    mc.nees_own += e.dot(P.ldlt().solve(e)) / nc / trials;
    mc.nees_report += e.dot(Pr.ldlt().solve(e)) / nc / trials;
    mc.nees_prior += ep.dot(P0.ldlt().solve(ep)) / nc / trials;
  }
  return mc;
}

FeatureLinearization rig_lin(const std::vector<std::pair<int, int64_t>> &cam_time, std::vector<CloneState> &clones) {
  FeatureLinearization lin;
  clones.resize(cam_time.size());
  for (size_t i = 0; i < cam_time.size(); ++i) {
    clones[i].t_cam_ns = cam_time[i].second;
    FeatureLinearization::Obs o;
    o.cam = cam_time[i].first;
    o.clone = &clones[i];
    lin.obs.push_back(o);
  }
  return lin;
}

} // namespace

// The rows' correlation: ρ^|Δk| within a camera, ρ_cam ρ^|Δk| across, k the image's rank among the feature's (cam1's
// track starts later and shares cam0's images); one camera without gaps is track_noise_factor's L Lᵀ.
TEST(StereoReportedCovariance, RigTrackCorrelationStructure) {
  std::vector<CloneState> clones;
  // cam0 at images 0..3, cam1 at 1..3 (linearize's order: the primary's first).
  const FeatureLinearization lin =
      rig_lin({{0, 100}, {0, 200}, {0, 300}, {0, 400}, {1, 200}, {1, 300}, {1, 400}}, clones);
  const double rho = 0.8, rc = 0.6;
  const Eigen::MatrixXd C = UpdaterMSCKF::rig_track_correlation(lin, rho, rc);
  ASSERT_EQ(C.rows(), 14);
  EXPECT_DOUBLE_EQ(C(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(C(0, 1), 0.0);                            // u and v apart
  EXPECT_DOUBLE_EQ(C(2 * 0, 2 * 3), rho * rho * rho);        // cam0 images 0 and 3
  EXPECT_DOUBLE_EQ(C(2 * 1, 2 * 4), rc);                     // cam0 and cam1 at image 1
  EXPECT_DOUBLE_EQ(C(2 * 3 + 1, 2 * 4 + 1), rc * rho * rho); // cam0 image 3, cam1 image 1 (v)
  EXPECT_DOUBLE_EQ(C(2 * 4, 2 * 6), rho * rho);              // cam1 images 1 and 3
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(C).eigenvalues().minCoeff(), 0.0);
  std::vector<CloneState> mono_clones;
  const FeatureLinearization mono = rig_lin({{0, 1}, {0, 2}, {0, 3}, {0, 4}, {0, 5}}, mono_clones);
  const Eigen::MatrixXd L = UpdaterMSCKF::track_noise_factor(10, rho);
  EXPECT_TRUE(UpdaterMSCKF::rig_track_correlation(mono, rho, rc).isApprox(L * L.transpose(), 1e-12));
}

// Stereo errors correlated across the cameras (AR(1) 0.9 in time, 0.9 between the cameras, 1 px) weighted as
// independent 1 px: the reported covariance that takes the cameras as independent is overconfident; with the cameras'
// correlation it is consistent. The estimate and the filter's own covariance are the same either way.
TEST(StereoReportedCovariance, CameraCorrelationMakesTheReportConsistent) {
  const RigMonteCarlo indep = rig_monte_carlo(0.9, 0.9, 0.0, 150, 11);
  const RigMonteCarlo corr = rig_monte_carlo(0.9, 0.9, 0.9, 150, 11);
  std::cout << "[stereo update MC, AR(1) 0.9, cameras 0.9] NEES/dim prior " << corr.nees_prior << ", own "
            << corr.nees_own << ", reported with cameras independent " << indep.nees_report
            << ", with their correlation " << corr.nees_report << "\n";
  EXPECT_NEAR(corr.nees_prior, 1.0, 0.1);
  EXPECT_GT(indep.nees_report, 1.08); // 1.15 measured; 1.00 with the correlation
  EXPECT_NEAR(corr.nees_report, 1.0, 0.12);
  EXPECT_EQ(indep.nees_own, corr.nees_own);
}

// Monocular features never see the option: the reported covariance after a cam0-only update is bit for bit the same.
TEST(StereoReportedCovariance, MonocularFeaturesUnchanged) {
  const Scene sc = make_scene(10, 20, 1.0, 0.0, 21);
  State s0 = make_state(sc, 0.0, 0.001, 0.003, 0.01);
  s0.start_report();
  State s1 = s0;
  ovton::core::FeatureDatabase db;
  observe_ar1(sc, db, 1.0, 0.9, 3);
  UpdaterMSCKFOptions a, b;
  a.covariance_track_correlation = b.covariance_track_correlation = 0.9;
  b.covariance_camera_correlation = 0.9;
  const VelocityProvider vp;
  UpdaterMSCKF(sc.calib, a, {euroc_cam1()}).update(s0, all_features(db), TdObservation::None, vp);
  UpdaterMSCKF(sc.calib, b, {euroc_cam1()}).update(s1, all_features(db), TdObservation::None, vp);
  EXPECT_TRUE(s0.P_report == s1.P_report);
  EXPECT_TRUE(s0.P == s1.P);
}
