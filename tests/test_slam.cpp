// SLAM features (ov_msckf_ton/update/updater_slam.h): the landmark measurement Jacobians against finite differences
// in the state's ⊞ convention, delayed initialisation consistent over Monte-Carlo trials, and a whole run.
#include "estimator_test_util.h"
#include "fd_check.h"
#include "ov_core/io/dataset.h"
#include "ov_core/math/so3.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_msckf_ton/state/state_helper.h"
#include "ov_msckf_ton/update/feature_jacobians.h"
#include "ov_msckf_ton/update/updater_slam.h"
#include "ov_sim/euroc_calib.h"
#include "ov_sim/simulator.h"
#include "sim_fixture.h"
#include "test_util.h"

#include <optional>
#include <random>

using namespace ovton::msckf;

namespace {

constexpr int64_t kT0 = 1403636579763555584;

/// A state with `n` clones along a short arc looking at the origin region, and t_d in the state.
struct SlamScene {
  ovton::core::CameraCalib calib = ovton::sim::euroc_cam0_calib();
  Eigen::Matrix3d R_BC = calib.T_BC.topLeftCorner<3, 3>();
  Eigen::Vector3d p_BC = calib.T_BC.topRightCorner<3, 1>();
  State state{true};

  explicit SlamScene(int n) {
    state.P = Eigen::MatrixXd::Identity(state.dim(), state.dim()) * 1e-6;
    for (int k = 0; k < n; ++k) {
      const double a = 0.05 * k;
      // Body x forward-ish; the camera (R_BC) then looks roughly along world +x.
      state.imu.R = ovton::core::so3_exp(Eigen::Vector3d(0.02 * k, -0.01 * k, 0.03 * k)) *
                    (Eigen::Matrix3d() << 0, 0, 1, -1, 0, 0, 0, -1, 0).finished() * R_BC.transpose();
      state.imu.p = Eigen::Vector3d(-3.0 + 0.1 * std::sin(a), 0.3 * a, 0.1 * a);
      state.t_imu_ns = kT0 + 50000000LL * k;
      state_helper::clone(state, kT0 + 50000000LL * k, false, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
    }
  }
  bool project(const CloneState &c, const Eigen::Vector3d &p_W, Eigen::Vector2d &xy) const {
    return project_in_clone(c.R, c.p, R_BC, p_BC, p_W, xy);
  }
};

ovton::core::Feature feature_of(const SlamScene &sc, const Eigen::Vector3d &p_W, double noise, std::mt19937 &rng) {
  std::normal_distribution<double> n(0, noise);
  ovton::core::CameraModel cam(sc.calib);
  ovton::core::Feature f;
  f.id = 7;
  for (const auto &[t, c] : sc.state.clones) {
    Eigen::Vector2d xy;
    EXPECT_TRUE(sc.project(c, p_W, xy));
    // Noise where the tracker makes it: in distorted pixels.
    ovton::core::FeatureObservation o;
    o.t_cam_ns = t;
    o.uv = cam.distort(xy) + Eigen::Vector2d(n(rng), n(rng));
    o.xy = cam.undistort(o.uv);
    xy = o.xy;
    if (!f.obs.empty()) {
      o.vel_xy = (xy - f.obs.back().xy) / 0.05;
      o.vel_valid = true;
    }
    f.obs.push_back(o);
  }
  return f;
}

/// Pixel errors of one track, AR(1) with correlation rho between consecutive images and stationary sigma.
std::vector<Eigen::Vector2d> ar1_errors(int n, double sigma, double rho, std::mt19937 &rng) {
  std::normal_distribution<double> g(0, 1);
  std::vector<Eigen::Vector2d> e(n);
  e[0] = sigma * Eigen::Vector2d(g(rng), g(rng));
  for (int k = 1; k < n; ++k)
    e[k] = rho * e[k - 1] + sigma * std::sqrt(1 - rho * rho) * Eigen::Vector2d(g(rng), g(rng));
  return e;
}

/// Landmark NEES over Monte-Carlo trials: initialised from the first `init` of 12 images (true clones), then updated
/// by each later image's observation, pixel errors AR(1) with `rho_true`, the filter told `rho_model`. rho_report > 0:
/// the weights stay independent and the NEES is the reported covariance's (update.covariance_track_correlation).
double landmark_nees_with_correlated_errors(double rho_true, double rho_model, double rho_report = 0.0, int init = 6) {
  const Eigen::Vector3d p_true(0.3, 0.2, -0.1);
  const int n = 12;
  std::mt19937 rng(9);
  double nees = 0;
  int trials = 0;
  for (int t = 0; t < 200; ++t) {
    SlamScene sc(n);
    sc.state.P *= 1e-8; // the clones are the truth: only the pixel noise is uncertain
    if (rho_report > 0)
      sc.state.start_report();
    ovton::core::CameraModel cam(sc.calib);
    const std::vector<Eigen::Vector2d> e = ar1_errors(n, 1.0, rho_true, rng);
    std::vector<std::pair<int64_t, Eigen::Vector2d>> uv;
    for (const auto &[t_ns, c] : sc.state.clones) {
      Eigen::Vector2d xy;
      EXPECT_TRUE(sc.project(c, p_true, xy));
      uv.emplace_back(t_ns, cam.distort(xy) + e[uv.size()]);
    }
    UpdaterMSCKFOptions mo;
    mo.chi2_multiplier = 100; // this test is about the covariance, not the gate
    mo.covariance_track_correlation = rho_report;
    UpdaterMSCKF msckf(sc.calib, mo);
    UpdaterSlamOptions so;
    so.chi2_multiplier = 100;
    so.track_correlation = rho_model;
    UpdaterSLAM slam(sc.calib, so, msckf);
    ovton::core::FeatureDatabase db;
    for (int k = 0; k < init; ++k)
      db.add_observation(7, uv[k].first, uv[k].second, cam.undistort(uv[k].second));
    SlamStats st;
    slam.initialize(sc.state, {db.get(7)}, uv[init - 1].first, TdObservation::None, VelocityProvider(), st);
    if (st.initialised != 1)
      continue;
    for (int k = init; k < n; ++k) {
      db.add_observation(7, uv[k].first, uv[k].second, cam.undistort(uv[k].second));
      std::vector<size_t> drop;
      slam.update(sc.state, db, uv[k].first, TdObservation::None, VelocityProvider(), st, drop);
      EXPECT_TRUE(drop.empty());
    }
    const LandmarkState &l = sc.state.landmarks.at(7);
    const Eigen::Vector3d err = p_true - l.p_W;
    nees += err.dot(sc.state.reported_block(l.index, l.index, 3, 3).ldlt().solve(err));
    ++trials;
  }
  EXPECT_GT(trials, 150);
  return nees / std::max(trials, 1);
}

} // namespace

// slam.track_correlation: with a track's errors correlated from image to image, the whitened initialisation and
// the differenced updates keep the landmark's covariance honest; taken as independent, the same errors make it
// overconfident (the test can fail both ways).
TEST(SlamInit, CorrelatedTrackErrorsKeepTheLandmarkConsistentWhenModelled) {
  const double modelled = landmark_nees_with_correlated_errors(0.8, 0.8);
  const double ignored = landmark_nees_with_correlated_errors(0.8, 0.0);
  const double independent = landmark_nees_with_correlated_errors(0.0, 0.0);
  std::cout << "[slam correlated] landmark NEES: modelled " << modelled << ", ignored " << ignored
            << ", independent errors " << independent << " (3 is ideal)\n";
  EXPECT_GT(modelled, 2.2);
  EXPECT_LT(modelled, 4.0);
  EXPECT_GT(ignored, 4.5);
  EXPECT_GT(independent, 2.2);
  EXPECT_LT(independent, 4.0);
}

// The reported covariance of a landmark initialised from a whole window of AR(1) errors, weighted as independent:
// report_initialization carries the window's correlation into the landmark's covariance (the split rows' mutual
// correlation left out), where the filter's own covariance is overconfident.
TEST(SlamInit, ReportedCovarianceOfAWindowInitialisationFollowsCorrelatedErrors) {
  const double own = landmark_nees_with_correlated_errors(0.8, 0.0, 0.0, 12);
  const double reported = landmark_nees_with_correlated_errors(0.8, 0.0, 0.8, 12);
  std::cout << "[slam report] landmark NEES from a 12-image window, AR(1) 0.8: own " << own << ", reported " << reported
            << " (3 is ideal)\n";
  EXPECT_GT(own, 4.5);
  EXPECT_GT(reported, 2.2);
  EXPECT_LT(reported, 4.0);
}

TEST(SlamJacobians, LandmarkMeasurementMatchesFiniteDifferences) {
  SlamScene sc(4);
  const Eigen::Vector3d p_f(0.4, -0.3, 0.2);
  std::mt19937 rng(1);
  const ovton::core::Feature f = feature_of(sc, p_f, 0.5, rng);
  LandmarkState l;
  l.p_W = l.p_fej = p_f + Eigen::Vector3d(0.01, -0.02, 0.015);
  l.index = sc.state.add_variable(Eigen::Matrix3d::Identity() * 1e-4);
  sc.state.landmarks[l.id] = l;
  sc.state.td = 0.004;
  CloneState &c = sc.state.clones.rbegin()->second;
  c.td_ref = 0.001;
  c.has_fej = false; // Jacobians at the current estimate, so that finite differences of the residual match them
  UpdaterMSCKF msckf(sc.calib);
  UpdaterSLAM slam(sc.calib, UpdaterSlamOptions(), msckf);
  const VelocityProvider tracked;
  const size_t k = f.obs.size() - 1;
  LandmarkLinearization lin;
  ASSERT_TRUE(slam.linearize(sc.state, sc.state.landmarks.at(l.id), c, f, k, TdObservation::ImagePlane, tracked, lin));
  ASSERT_TRUE(lin.td_column);
  // r = z − h: H is −∂r/∂δx. Perturb the clone (⊞), the landmark and t_d one coordinate at a time.
  const auto residual = [&](const Eigen::Matrix<double, 10, 1> &d) {
    State s = sc.state;
    CloneState &cc = s.clones.rbegin()->second;
    cc.R = ovton::core::so3_exp(d.segment<3>(0)) * cc.R;
    cc.p += d.segment<3>(3);
    LandmarkState &ll = s.landmarks.at(l.id);
    ll.p_W += d.segment<3>(6);
    ll.p_fej = ll.p_W;
    s.td += d(9);
    LandmarkLinearization out;
    EXPECT_TRUE(slam.linearize(s, ll, cc, f, k, TdObservation::ImagePlane, tracked, out));
    return out.r;
  };
  Eigen::Matrix<double, 2, 10> H;
  H << lin.H_clone, lin.H_f, lin.H_td;
  const Eigen::MatrixXd H_fd = -ovtest::numeric_jacobian(residual, Eigen::Matrix<double, 10, 1>::Zero().eval(), 1e-6);
  EXPECT_LT((H - H_fd).cwiseAbs().maxCoeff(), 1e-5 * H.cwiseAbs().maxCoeff()) << "analytic\n"
                                                                              << H << "\nnumeric\n"
                                                                              << H_fd;
}

/// A body turning and moving, a camera on it and a point in front: the predicted image velocity's test case.
struct MovingCamera {
  Eigen::Matrix3d R_WB = ovton::core::so3_exp(Eigen::Vector3d(0.2, -0.4, 1.1));
  Eigen::Vector3d p_WB{0.3, -0.2, 1.0}, p_W{2.5, 0.8, 1.4};
  Eigen::Matrix3d R_BC = ovton::core::so3_exp(Eigen::Vector3d(-1.2, 0.1, -1.5));
  Eigen::Vector3d p_BC{0.05, -0.02, 0.01};
  BodyMotion m{Eigen::Vector3d(0.7, -1.3, 0.4), Eigen::Vector3d(-0.6, 0.9, 0.3)};
};

TEST(SlamJacobians, PredictedImageVelocityIsTheProjectionsTimeDerivative) {
  // The body turning at ω (Ṙ_WB = R_WB [ω]×) and moving at v: the landmark's normalised image point over time,
  // differentiated numerically, against predicted_image_velocity.
  const MovingCamera mc;
  const Eigen::Matrix3d &R_WB = mc.R_WB, &R_BC = mc.R_BC;
  const Eigen::Vector3d &p_WB = mc.p_WB, &p_W = mc.p_W, &p_BC = mc.p_BC;
  const BodyMotion &m = mc.m;
  auto z_at = [&](const Eigen::Matrix<double, 1, 1> &t) {
    Eigen::Vector2d z;
    const bool ok =
        project_in_clone(R_WB * ovton::core::so3_exp(m.w_B * t(0)), p_WB + m.v_W * t(0), R_BC, p_BC, p_W, z);
    EXPECT_TRUE(ok);
    return z;
  };
  Eigen::Vector2d vel;
  ASSERT_TRUE(predicted_image_velocity(R_WB, p_WB, R_BC, p_BC, p_W, m, vel));
  const Eigen::MatrixXd numeric = ovtest::numeric_jacobian(z_at, Eigen::Matrix<double, 1, 1>::Zero().eval(), 1e-6);
  EXPECT_GT(vel.norm(), 0.1); // a real motion on the image
  EXPECT_LT((numeric.col(0) - vel).norm(), 1e-6 * vel.norm()) << numeric.transpose() << " vs " << vel.transpose();
  // Behind the camera: no velocity.
  EXPECT_FALSE(predicted_image_velocity(R_WB, p_WB, R_BC, p_BC, p_WB - 3.0 * (R_WB * R_BC).col(2), m, vel));
}

TEST(SlamJacobians, PredictedImageVelocityJacobiansMatchFiniteDifferences) {
  // V's Jacobians w.r.t. the clone's [δθ δp], the point and the extrinsics [δθ_BC δp_BC], each in the state's ⊞.
  const MovingCamera mc;
  const Eigen::Matrix3d &R_WB = mc.R_WB, &R_BC = mc.R_BC;
  const Eigen::Vector3d &p_WB = mc.p_WB, &p_W = mc.p_W, &p_BC = mc.p_BC;
  const BodyMotion &m = mc.m;
  const auto vel_at = [&](const Eigen::Matrix<double, 15, 1> &d) {
    Eigen::Vector2d v;
    EXPECT_TRUE(predicted_image_velocity(ovton::core::so3_exp(d.segment<3>(0)) * R_WB, p_WB + d.segment<3>(3),
                                         ovton::core::so3_exp(d.segment<3>(9)) * R_BC, p_BC + d.segment<3>(12),
                                         p_W + d.segment<3>(6), m, v));
    return v;
  };
  Eigen::Vector2d v;
  CloneMeasurementJacobians J;
  ASSERT_TRUE(predicted_image_velocity(R_WB, p_WB, R_BC, p_BC, p_W, m, v, &J));
  Eigen::Matrix<double, 2, 15> H;
  H << J.H_theta, J.H_p, J.H_f, J.H_ext_theta, J.H_ext_p;
  const Eigen::MatrixXd H_fd = ovtest::numeric_jacobian(vel_at, Eigen::Matrix<double, 15, 1>::Zero().eval(), 1e-6);
  EXPECT_LT((H - H_fd).cwiseAbs().maxCoeff(), 1e-6 * H.cwiseAbs().maxCoeff()) << "analytic\n"
                                                                              << H << "\nnumeric\n"
                                                                              << H_fd;
}

TEST(SlamInit, DelayedInitialisationIsConsistentOverMonteCarloTrials) {
  // The same window, noisy observations: the initialised landmark's error against the truth, normalised by its
  // covariance, averages 3 (its dimension) when the initialisation's covariance is right.
  const Eigen::Vector3d p_true(0.3, 0.2, -0.1);
  std::mt19937 rng(5);
  double nees = 0;
  int trials = 0;
  for (int t = 0; t < 300; ++t) {
    SlamScene sc(8);
    sc.state.P *= 1e-8; // the clones are the truth: only the pixel noise is uncertain
    const ovton::core::Feature f = feature_of(sc, p_true, 1.0, rng);
    UpdaterMSCKFOptions mo;
    mo.chi2_multiplier = 100; // this test is about the covariance, not the gate
    UpdaterMSCKF msckf(sc.calib, mo);
    UpdaterSlamOptions so;
    so.chi2_multiplier = 100;
    UpdaterSLAM slam(sc.calib, so, msckf);
    SlamStats st;
    slam.initialize(sc.state, {&f}, sc.state.clones.rbegin()->first, TdObservation::None, VelocityProvider(), st);
    if (st.initialised != 1)
      continue;
    const LandmarkState &l = sc.state.landmarks.at(f.id);
    const Eigen::Vector3d e = p_true - l.p_W;
    const Eigen::Matrix3d P = sc.state.P.block<3, 3>(l.index, l.index);
    nees += e.dot(P.ldlt().solve(e));
    ++trials;
  }
  ASSERT_GT(trials, 250);
  nees /= trials;
  std::cout << "[slam init] landmark NEES " << nees << " over " << trials << " trials (3 is ideal)\n";
  EXPECT_GT(nees, 2.2);
  EXPECT_LT(nees, 4.0);
}

TEST(SlamRun, LandmarksEnterLeaveAndKeepTheFilterConsistent) {
  ovtest::TempDir tmp;
  const ovton::core::Dataset data = ovtest::feature_flight(tmp / "sim", 10.0, 4, 0.5);
  VioOptions opt = ovtest::gt_run_options(TdMode::Sr, 0.5);
  opt.slam.max_features = 50;
  size_t max_landmarks = 0;
  std::optional<State> last;
  const auto run = ovtest::run_estimator(data, opt, {ovtest::peek([&](const VioManager &f) {
                                           max_landmarks = std::max(max_landmarks, f.state().landmarks.size());
                                           last = f.state();
                                         })});
  ASSERT_TRUE(last);
  const VioCounters &c = run.report.counters;
  std::cout << "[slam run] " << c.slam_initialised << " landmarks initialised, " << c.slam_updates
            << " observations used, " << c.slam_gated << " gated; at most " << max_landmarks << " in the state\n";
  EXPECT_GT(c.slam_initialised, 50);
  EXPECT_LE(max_landmarks, 50u);
  EXPECT_GT(c.slam_updates, 5 * c.slam_initialised);
  // Gated at 95 %: about 5 % of consistent observations fail the test.
  EXPECT_LT(c.slam_gated, 0.15 * (c.slam_updates + c.slam_gated));
  // Every landmark index is inside the covariance and distinct.
  std::set<int> idx;
  for (const auto &[id, l] : last->landmarks) {
    EXPECT_GE(l.index, 0);
    EXPECT_LE(l.index + 3, last->dim());
    EXPECT_TRUE(idx.insert(l.index).second);
  }
}
