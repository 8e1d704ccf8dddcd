// MSCKF update: measurement Jacobians and the image-plane t_d column against finite differences in the state's ⊞
// convention, nullspace projection, triangulation accuracy, full updates on synthetic scenes (pose correction,
// chi-square gating of an outlier, t_d recovery in image-plane mode) and the residual log.
#include "fd_check.h"
#include "ov_core/cam/camera_model.h"
#include "ov_core/math/so3.h"
#include "ov_core/track/feature_database.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/state/state_helper.h"
#include "ov_msckf_ton/update/feature_jacobians.h"
#include "ov_msckf_ton/update/residual_log.h"
#include "ov_msckf_ton/update/triangulation.h"
#include "ov_msckf_ton/update/updater_msckf.h"
#include "ov_sim/euroc_calib.h"
#include "test_util.h"
#include "update_test_util.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <sstream>

using namespace ovton::msckf;
using ovton::core::so3_exp;
using ovton::core::so3_log;

using namespace updtest;

TEST(UpdateJacobians, CloneAndFeatureJacobiansMatchFiniteDifferences) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0, 1);
  const ovton::core::CameraCalib calib = euroc_cam0();
  const Eigen::Matrix3d R_BC = calib.T_BC.topLeftCorner<3, 3>();
  const Eigen::Vector3d p_BC = calib.T_BC.topRightCorner<3, 1>();
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Matrix3d R = so3_exp(Eigen::Vector3d(n(rng), n(rng), n(rng)));
    const Eigen::Vector3d p(n(rng), n(rng), n(rng));
    const Eigen::Vector3d p_C(0.5 * n(rng), 0.5 * n(rng), 2.0 + std::abs(n(rng)));
    const Eigen::Vector3d p_f = R * (R_BC * p_C + p_BC) + p;
    Eigen::Vector2d z0;
    CloneMeasurementJacobians J;
    ASSERT_TRUE(project_in_clone(R, p, R_BC, p_BC, p_f, z0, nullptr, &J));
    const auto z = [&](const Eigen::Matrix3d &Ri, const Eigen::Vector3d &pi, const Eigen::Vector3d &p_fi) {
      Eigen::Vector2d zi;
      project_in_clone(Ri, pi, R_BC, p_BC, p_fi, zi);
      return zi;
    };
    const double h = 1e-6;
    const Eigen::MatrixXd Nth = ovtest::numeric_jacobian([&](const Eigen::Matrix3d &Ri) { return z(Ri, p, p_f); }, R, 3,
                                                         ovtest::rotation_plus, h);
    const Eigen::MatrixXd Np = ovtest::numeric_jacobian([&](const Eigen::Vector3d &pi) { return z(R, pi, p_f); }, p, h);
    const Eigen::MatrixXd Nf =
        ovtest::numeric_jacobian([&](const Eigen::Vector3d &p_fi) { return z(R, p, p_fi); }, p_f, h);
    EXPECT_LT((Nth - J.H_theta).norm(), 1e-7 * (1 + J.H_theta.norm())) << "trial " << trial;
    EXPECT_LT((Np - J.H_p).norm(), 1e-7 * (1 + J.H_p.norm())) << "trial " << trial;
    EXPECT_LT((Nf - J.H_f).norm(), 1e-7 * (1 + J.H_f.norm())) << "trial " << trial;
  }
  Eigen::Vector2d z;
  EXPECT_FALSE(project_in_clone(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(),
                                Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, -1), z));
}

// The whole linearisation as the updater builds it, in ImagePlane mode with t̂_d ≠ td_ref so the shift is active:
// every compact column (clone δθ, δp and t_d) against ⊞-perturbed states, and H_f against a moved feature.
TEST(UpdateJacobians, StackedFeatureJacobianIncludingTdColumnMatchesFiniteDifferences) {
  const Scene sc = make_scene(6, 5, 2.0, 0.0, 11);
  ASSERT_EQ(sc.points.size(), 5u);
  State s = make_state(sc, 0.0, 0.01, 0.02, 0.02);
  s.td = 0.007; // t̂_d moved since cloning: V·(t̂_d − td_ref) is non-zero
  ovton::core::FeatureDatabase db;
  observe(sc, db, 0.0, 1);
  const ovton::core::Feature &f = *db.get(2);
  const Eigen::Vector3d p_f = sc.points[2] + Eigen::Vector3d(0.01, -0.02, 0.03);
  UpdaterMSCKF up(sc.calib);
  // Every row needs a velocity for the feature to carry t_d: the first one borrows the second's (as FVON would
  // predict one).
  struct FillFirst : VelocityProvider {
    bool velocity(const ovton::core::Feature &feat, size_t i, Eigen::Vector2d &v, int &src) const override {
      v = feat.obs[i == 0 ? 1 : i].vel_xy;
      src = i == 0 ? kVelocityItsFvon : kVelocityTracked;
      return true;
    }
  } vp;
  FeatureLinearization lin;
  ASSERT_TRUE(up.linearize(s, f, p_f, TdObservation::ImagePlane, vp, lin));
  const int m = 6;
  ASSERT_EQ(lin.r.size(), 2 * m);
  ASSERT_EQ(static_cast<int>(lin.cols.size()), 6 * m + 1);
  EXPECT_EQ(lin.cols.back(), s.td_index);
  for (int k = 0; k < m; ++k)
    EXPECT_TRUE(lin.obs[k].td_column);
  // Without a velocity for the first row, no row of the feature carries t_d (all or nothing).
  FeatureLinearization plain;
  ASSERT_TRUE(up.linearize(s, f, p_f, TdObservation::ImagePlane, VelocityProvider(), plain));
  EXPECT_EQ(static_cast<int>(plain.cols.size()), 6 * m);

  expect_linearization_matches_fd(up, s, f, p_f, TdObservation::ImagePlane, vp, lin);
  // The t_d column is +V (model form) on rows that have a velocity, in distorted pixels like every row.
  for (int k = 1; k < m; ++k)
    EXPECT_LT((lin.H_x.block<2, 1>(2 * k, 6 * m) - up.distortion_jacobian(f.obs[k].xy) * f.obs[k].vel_xy).norm(), 1e-9);

  // StateRelevant / None add no t_d column and no shift.
  FeatureLinearization lp;
  ASSERT_TRUE(up.linearize(s, f, p_f, TdObservation::StateRelevant, vp, lp));
  EXPECT_EQ(static_cast<int>(lp.cols.size()), 6 * m);
  EXPECT_GT((lp.r - lin.r).norm(), 1e-6);
}

TEST(UpdateNullspace, ProjectionAnnihilatesFeatureJacobianAndKeepsResidualConsistent) {
  const Scene sc = make_scene(8, 3, 1.0, 0.0, 5);
  const State s = make_state(sc, 0.0, 0.01, 0.02, 0.02);
  ovton::core::FeatureDatabase db;
  observe(sc, db, 0.0, 2);
  UpdaterMSCKF up(sc.calib);
  VelocityProvider vp;
  FeatureLinearization lin;
  ASSERT_TRUE(up.linearize(s, *db.get(1), sc.points[1], TdObservation::ImagePlane, vp, lin));
  const int rows = static_cast<int>(lin.r.size()), nc = static_cast<int>(lin.cols.size());

  // A residual generated exactly by the linear model r = H_x dx + H_f df.
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  Eigen::VectorXd dx(nc);
  for (int i = 0; i < nc; ++i)
    dx(i) = 0.01 * n(rng);
  const Eigen::Vector3d df(0.3, -0.2, 0.5);
  const Eigen::VectorXd r_lin = lin.H_x * dx + lin.H_f * df;

  // Project [H_x | H_f] together so that the projected H_f can be inspected.
  Eigen::MatrixXd M(rows, nc + 3);
  M << lin.H_x, lin.H_f;
  Eigen::VectorXd r = r_lin;
  UpdaterMSCKF::nullspace_project(lin.H_f, M, r);
  ASSERT_EQ(M.rows(), rows - 3);
  ASSERT_EQ(r.size(), rows - 3);
  EXPECT_LT(M.rightCols(3).norm(), 1e-12 * lin.H_f.norm());
  EXPECT_LT((r - M.leftCols(nc) * dx).norm(), 1e-12 * (1 + r_lin.norm()));
  // Q₂ has orthonormal columns: the projection cannot lengthen a vector.
  Eigen::VectorXd w = Eigen::VectorXd::NullaryExpr(rows, [&]() { return n(rng); });
  Eigen::MatrixXd Hw = lin.H_f; // same H_f, any H_x
  Eigen::MatrixXd dummy = Eigen::MatrixXd::Zero(rows, 1);
  Eigen::VectorXd wp = w;
  UpdaterMSCKF::nullspace_project(lin.H_f, dummy, wp);
  EXPECT_LE(wp.norm(), w.norm() + 1e-12);

  // Compression keeps HᵀH and Hᵀr (the information the EKF sees).
  Eigen::MatrixXd H = M.leftCols(nc);
  Eigen::MatrixXd Hs(2 * H.rows(), nc);
  Hs << H, 0.5 * H;
  Eigen::VectorXd rs(2 * r.size());
  rs << r, 0.3 * r;
  const Eigen::MatrixXd HtH = Hs.transpose() * Hs;
  const Eigen::VectorXd Htr = Hs.transpose() * rs;
  UpdaterMSCKF::compress(Hs, rs);
  EXPECT_LE(Hs.rows(), nc);
  EXPECT_LT((Hs.transpose() * Hs - HtH).norm(), 1e-10 * HtH.norm());
  EXPECT_LT((Hs.transpose() * rs - Htr).norm(), 1e-10 * (1 + Htr.norm()));
}

TEST(UpdateTriangulation, RecoversPointFromFiveNoisyViews) {
  std::mt19937 rng(42);
  std::normal_distribution<double> n(0, 1);
  const double f = 458.0, noise_px = 0.5;
  TriangulationOptions opt;
  double sum2 = 0.0, worst = 0.0;
  const int trials = 50;
  for (int trial = 0; trial < trials; ++trial) {
    const Eigen::Vector3d p_W(0.2 * n(rng), 0.2 * n(rng), 3.0);
    std::vector<CameraPose> poses;
    std::vector<Eigen::Vector2d> xy;
    for (int i = 0; i < 5; ++i) {
      CameraPose cp;
      // 2 m of baseline: with 1 m the Cramér-Rao bound on depth alone is σ·Z²/√Σ(c−c̄)² = 1.24 cm at 0.5 px.
      cp.p_WC = Eigen::Vector3d(-1.0 + 0.5 * i, 0.1 * std::sin(i), 0.05 * i);
      cp.R_WC = so3_exp(Eigen::Vector3d(0.02 * i, 0.3 - 0.15 * i, 0.03)); // toed in towards the point
      const Eigen::Vector3d p_C = cp.R_WC.transpose() * (p_W - cp.p_WC);
      xy.emplace_back(p_C.x() / p_C.z() + noise_px / f * n(rng), p_C.y() / p_C.z() + noise_px / f * n(rng));
      poses.push_back(cp);
    }
    const TriangulationResult res = triangulate(poses, xy, 4, opt);
    ASSERT_TRUE(res.ok()) << to_string(res.quality);
    const double err = (res.p_W - p_W).norm();
    sum2 += err * err;
    worst = std::max(worst, err);
    EXPECT_LT(res.reproj_rms * f, 2.5 * noise_px); // E[rms] = σ·√(2·(5−1.5)/5) ≈ 0.59 px
  }
  const double rms = std::sqrt(sum2 / trials);
  std::cout << "[ triangulation ] 3 m point, 5 views over 2 m, 0.5 px: RMS error " << rms * 100 << " cm, worst "
            << worst * 100 << " cm over " << trials << " trials\n";
  EXPECT_LT(rms, 0.01);
  EXPECT_LT(worst, 0.025);
}

TEST(UpdateTriangulation, RejectsDegenerateGeometry) {
  TriangulationOptions opt;
  const Eigen::Vector3d p_W(0.1, 0.2, 4.0);
  auto obs = [&](const CameraPose &cp) {
    const Eigen::Vector3d p_C = cp.R_WC.transpose() * (p_W - cp.p_WC);
    return Eigen::Vector2d(p_C.x() / p_C.z(), p_C.y() / p_C.z());
  };
  std::vector<CameraPose> poses(1);
  std::vector<Eigen::Vector2d> xy{obs(poses[0])};
  EXPECT_EQ(triangulate(poses, xy, 0, opt).quality, TriangulationQuality::TooFewObservations);
  // Pure rotation: no parallax, whatever the rotation.
  for (int i = 1; i < 4; ++i) {
    CameraPose cp;
    cp.R_WC = so3_exp(Eigen::Vector3d(0, 0.05 * i, 0));
    poses.push_back(cp);
    xy.push_back(obs(cp));
  }
  EXPECT_EQ(triangulate(poses, xy, 0, opt).quality, TriangulationQuality::LowParallax);
  // Rays that meet behind the cameras.
  for (int i = 1; i < 4; ++i) {
    poses[i].p_WC = Eigen::Vector3d(0.3 * i, 0, 0);
    xy[i] = obs(poses[i]);
  }
  ASSERT_TRUE(triangulate(poses, xy, 0, opt).ok());
  std::vector<Eigen::Vector2d> flipped = xy;
  for (int i = 1; i < 4; ++i)
    flipped[i].x() = 2 * xy[0].x() - xy[i].x();
  EXPECT_EQ(triangulate(poses, flipped, 0, opt).quality, TriangulationQuality::BadDepth);
  // Depth limit.
  TriangulationOptions near = opt;
  near.max_depth = 2.0;
  EXPECT_EQ(triangulate(poses, xy, 0, near).quality, TriangulationQuality::BadDepth);
  EXPECT_THROW(triangulate(poses, std::vector<Eigen::Vector2d>(2), 0, opt), ovton::core::UsageError);
}

TEST(UpdateMsckf, ChiSquareTableMatchesKnownQuantiles) {
  UpdaterMSCKF up(euroc_cam0());
  EXPECT_NEAR(up.chi2_threshold(1), 3.841459, 1e-5);
  EXPECT_NEAR(up.chi2_threshold(10), 18.307038, 1e-5);
  EXPECT_NEAR(up.chi2_threshold(600), 658.09, 0.1); // beyond the cached table
  // Residual rows are in distorted pixels: at the principal point the scaling is the focal lengths.
  const Eigen::Matrix2d Jd = up.distortion_jacobian(Eigen::Vector2d::Zero());
  EXPECT_NEAR((Jd - Eigen::Vector2d(euroc_cam0().intrinsics.head<2>()).asDiagonal().toDenseMatrix()).norm(), 0, 1e-9);
  UpdaterMSCKFOptions bad;
  bad.min_observations = 1;
  EXPECT_THROW(UpdaterMSCKF(euroc_cam0(), bad), ovton::core::UsageError);
}

TEST(UpdateMsckf, FullUpdateCorrectsPerturbedCloneAndKeepsCovariancePsd) {
  const Scene sc = make_scene(10, 50, 1.0, 0.0, 21);
  ASSERT_GE(sc.points.size(), 45u);
  State s = make_state(sc, 0.0, 0.02, 0.05, 0.02);
  // Plant a pose error on one clone.
  CloneState &bad = s.clones[sc.stamps[5]];
  bad.R = bad.R * so3_exp(Eigen::Vector3d(0.01, -0.008, 0.005));
  bad.p += Eigen::Vector3d(0.04, -0.03, 0.02);
  const auto [eth0, ep0] = clone_error(sc, bad, 0.0);
  ovton::core::FeatureDatabase db;
  observe(sc, db, 0.0, 3);
  UpdaterMSCKF up(sc.calib);
  VelocityProvider vp;
  const UpdateStats st = up.update(s, all_features(db), TdObservation::None, vp);
  const auto [eth1, ep1] = clone_error(sc, s.clones[sc.stamps[5]], 0.0);
  std::cout << "[ full update ] used " << st.features_used << "/" << st.features_in << " features, " << st.rows_stacked
            << " rows -> " << st.rows_update << "; perturbed clone error " << eth0 * 180 / M_PI << " deg / "
            << ep0 * 100 << " cm -> " << eth1 * 180 / M_PI << " deg / " << ep1 * 100 << " cm\n";
  EXPECT_EQ(st.features_used, static_cast<int>(sc.points.size()));
  EXPECT_EQ(st.rejected_triangulation, 0);
  EXPECT_EQ(st.gated_chi2, 0);
  EXPECT_EQ(st.rows_stacked, static_cast<int>(sc.points.size()) * (2 * 10 - 3));
  EXPECT_LE(st.rows_update, s.dim());
  // Only relative poses are observable: the planted error is shared among the ten equally uncertain clones, so
  // about a tenth of it stays (as a common offset).
  EXPECT_LT(eth1, 0.3 * eth0);
  EXPECT_LT(ep1, 0.3 * ep0);
  for (const auto &[t, c] : s.clones) {
    const auto [eth, ep] = clone_error(sc, c, 0.0);
    EXPECT_LT(eth, 0.3 * eth0);
    EXPECT_LT(ep, 0.3 * ep0);
  }
  EXPECT_LT((s.P - s.P.transpose()).norm(), 1e-15 * s.P.norm());
  EXPECT_GT(state_helper::min_eigenvalue(s), -1e-12);
  EXPECT_EQ(st.td_after, st.td_before); // None: t_d untouched
}

TEST(UpdateMsckf, ChiSquareGatesPlantedOutlier) {
  const Scene sc = make_scene(8, 30, 1.0, 0.0, 33);
  ASSERT_GE(sc.points.size(), 25u);
  State s = make_state(sc, 0.0, 0.002, 0.005, 0.02);
  ovton::core::FeatureDatabase db;
  observe(sc, db, 0.0, 4);
  // Rebuild feature 7 with a 20 px jump in one observation.
  const size_t out_id = 7;
  db.remove(out_id);
  for (size_t k = 0; k < sc.stamps.size(); ++k) {
    Eigen::Vector2d xy;
    sc.project(sc.pose_at(sc.t_of(sc.stamps[k])), sc.points[out_id], xy);
    Eigen::Vector2d uv = sc.cam.distort(xy);
    if (k == 4)
      uv.x() += 20.0;
    db.add_observation(out_id, sc.stamps[k], uv, sc.cam.undistort(uv));
  }
  UpdaterMSCKF up(sc.calib);
  VelocityProvider vp;
  std::vector<ResidualRecord> log;
  const UpdateStats st = up.update(s, all_features(db), TdObservation::StateRelevant, vp, &log);
  EXPECT_EQ(st.gated_chi2, 1);
  EXPECT_EQ(st.features_used, static_cast<int>(sc.points.size()) - 1);
  int out_rows = 0;
  for (const ResidualRecord &r : log) {
    if (r.feature_id == out_id) {
      ++out_rows;
      EXPECT_EQ(r.accepted, 0);
      EXPECT_EQ(r.status, ResidualStatus::GatedChi2);
      EXPECT_GT(r.chi2, r.chi2_threshold);
      std::cout << (out_rows == 1 ? "[ outlier ] chi2 " + std::to_string(r.chi2) + " vs threshold " +
                                        std::to_string(r.chi2_threshold) + "\n"
                                  : "");
    } else {
      EXPECT_EQ(r.accepted, 1);
      EXPECT_LT(r.chi2, r.chi2_threshold);
    }
  }
  EXPECT_EQ(out_rows, static_cast<int>(sc.stamps.size()));
}

/// Velocities of the true motion at each observation's true time, for every observation including each track's
/// first: what a perfect FVON would supply (first observations marked as F2F predictions).
class TrueVelocities : public VelocityProvider {
public:
  explicit TrueVelocities(const Scene &sc) : sc_(sc) {}
  bool velocity(const ovton::core::Feature &f, size_t i, Eigen::Vector2d &v, int &src) const override {
    const double t = sc_.t_of(f.obs[i].t_cam_ns) + sc_.td_true, h = 1e-5;
    Eigen::Vector2d a, b;
    sc_.project(sc_.pose_at(t + h), sc_.points[f.id], a);
    sc_.project(sc_.pose_at(t - h), sc_.points[f.id], b);
    v = (a - b) / (2 * h);
    src = i == 0 ? kVelocityF2fFvon : kVelocityTracked;
    return true;
  }

private:
  const Scene &sc_;
};

TEST(UpdateMsckf, ImagePlaneUpdatePullsTdTowardTruth) {
  const double td_true = 0.010;
  const Scene sc = make_scene(10, 50, 2.5, td_true, 55);
  ASSERT_GE(sc.points.size(), 40u);
  ovton::core::FeatureDatabase db;
  observe(sc, db, 0.3, 5);
  UpdaterMSCKF up(sc.calib);
  VelocityProvider vp;

  // Clones placed with t̂_d = 0 (exact poses at t_cam), observations taken at t_cam + 10 ms.
  State s = make_state(sc, 0.0, 0.002, 0.004, 0.02);
  const UpdateStats st = up.update(s, all_features(db), TdObservation::ImagePlane, vp);
  double mean_vel_px = 0.0;
  int nv = 0;
  for (const auto &[id, f] : db.features())
    for (const auto &o : f.obs)
      if (o.vel_valid) {
        mean_vel_px += o.vel_uv.norm();
        ++nv;
      }
  mean_vel_px /= nv;
  // Each track's first observation here has no velocity. A feature carries t_d only when all its rows do: a row
  // without V would be modelled as not moving with t_d, which pins t̂_d to td_ref (spurious information). So
  // tracked velocities alone leave t_d untouched, and velocities for every row (what FVON supplies) recover it.
  State s_all = make_state(sc, 0.0, 0.002, 0.004, 0.02);
  const UpdateStats st_all = up.update(s_all, all_features(db), TdObservation::ImagePlane, TrueVelocities(sc));
  std::cout << "[ image-plane t_d ] mean image speed " << mean_vel_px << " px/s, truth " << td_true * 1e3
            << " ms, prior 0 ± 20 ms:\n  tracked velocities (" << st.td_obs_used[kVelocityTracked] << " rows): t_d "
            << s.td * 1e3 << " ± " << s.td_sigma() * 1e3 << " ms\n  true velocities on every row ("
            << st_all.td_obs_used[kVelocityTracked] + st_all.td_obs_used[kVelocityF2fFvon] << " rows): t_d "
            << s_all.td * 1e3 << " ± " << s_all.td_sigma() * 1e3 << " ms\n";
  EXPECT_EQ(st.features_used, static_cast<int>(sc.points.size()));
  EXPECT_EQ(st.td_features_used, 0);
  EXPECT_EQ(s.td, 0.0);
  EXPECT_LT(std::abs(s_all.td - td_true), 0.1 * td_true);
  EXPECT_LT(s_all.td_sigma(), 0.005);
  EXPECT_GT(std::abs(s_all.td - td_true), 0.0);
  EXPECT_EQ(st_all.td_features_used, st_all.features_used);
  EXPECT_EQ(st_all.td_obs_used[kVelocityF2fFvon], static_cast<int>(sc.points.size()));
  EXPECT_EQ(st_all.td_obs_used[kVelocityTracked], static_cast<int>(sc.points.size()) * 9);
  EXPECT_GT(state_helper::min_eigenvalue(s), -1e-12);

  // The same data without the image-plane model leaves t_d where it was.
  State s2 = make_state(sc, 0.0, 0.002, 0.004, 0.02);
  up.update(s2, all_features(db), TdObservation::StateRelevant, vp);
  EXPECT_EQ(s2.td, 0.0);
}

/// FVON-style provider: claims every observation, first ones as F2F predictions.
class AllVelocities : public VelocityProvider {
public:
  bool velocity(const ovton::core::Feature &f, size_t i, Eigen::Vector2d &v, int &src) const override {
    if (f.obs[i].vel_valid) {
      v = f.obs[i].vel_xy;
      src = kVelocityTracked;
    } else {
      v = f.obs[i + 1].vel_xy;
      src = kVelocityF2fFvon;
    }
    return true;
  }
};

TEST(UpdateMsckf, VelocityProviderSourcesAreCounted) {
  const Scene sc = make_scene(6, 10, 2.0, 0.0, 9);
  ovton::core::FeatureDatabase db;
  observe(sc, db, 0.0, 6);
  UpdaterMSCKF up(sc.calib);
  State s = make_state(sc, 0.0, 0.005, 0.01, 0.02);
  const UpdateStats st = up.update(s, all_features(db), TdObservation::ImagePlane, AllVelocities());
  const int nf = static_cast<int>(sc.points.size());
  EXPECT_EQ(st.td_obs_used[kVelocityTracked], nf * 5);
  EXPECT_EQ(st.td_obs_used[kVelocityF2fFvon], nf);
}

TEST(UpdateMsckf, ResidualLogHasHeaderAndOneRowPerObservation) {
  const Scene sc = make_scene(7, 12, 1.0, 0.0, 77);
  ASSERT_GE(sc.points.size(), 10u);
  ovton::core::FeatureDatabase db;
  observe(sc, db, 0.0, 7);
  UpdaterMSCKF up(sc.calib);
  VelocityProvider vp;
  State s = make_state(sc, 0.0, 0.005, 0.01, 0.02);
  for (auto &[t, c] : s.clones) { // the motion the clones were placed with: the log's body rate
    c.has_motion = true;
    c.motion.w_B = Eigen::Vector3d(0.1, -0.2, 0.3);
  }
  std::vector<ResidualRecord> log;
  up.update(s, all_features(db), TdObservation::ImagePlane, vp, &log);
  const size_t expected_rows = sc.points.size() * sc.stamps.size();
  ASSERT_EQ(log.size(), expected_rows);
  for (const ResidualRecord &r : log) {
    EXPECT_EQ(r.update_id, 1u);
    EXPECT_LT(std::hypot(r.res_u_px, r.res_v_px), 0.05); // perfect data at the true poses
    EXPECT_GT(r.depth_m, 2.0);
    EXPECT_EQ(r.vel_source, r.obs_index == 0 ? 0 : 1);
    EXPECT_EQ(r.td_column, 0); // the first row has no velocity, so no row of the feature carries t_d
    EXPECT_EQ(r.w_valid, 1);
    EXPECT_EQ(r.track_length, static_cast<int>(sc.stamps.size()));
  }

  ovtest::TempDir dir;
  const std::string path = dir / "residuals.csv";
  {
    ResidualLogWriter w(path);
    w.write(log);
    // Flushed per batch: the file is complete before the writer closes.
    std::ifstream in(path);
    std::string line;
    size_t n = 0;
    while (std::getline(in, line))
      ++n;
    EXPECT_EQ(n, expected_rows + 1);
    EXPECT_EQ(w.rows_written(), expected_rows);
  }
  std::ifstream in(path);
  std::string header, line;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("update_id,t_cam_ns,feature_id,obs_index,track_length,res_u_px,res_v_px,u_px,v_px,"
                         "vel_u_px_s,vel_v_px_s,vel_source,depth_m,radius_norm,w_x,w_y,w_z,td_s,chi2,"
                         "chi2_threshold,accepted",
                         0),
            0u);
  const auto ncols = std::count(header.begin(), header.end(), ',') + 1;
  size_t rows = 0;
  while (std::getline(in, line)) {
    EXPECT_EQ(std::count(line.begin(), line.end(), ',') + 1, ncols);
    ++rows;
  }
  EXPECT_EQ(rows, expected_rows);
  EXPECT_THROW(ResidualLogWriter("/nonexistent_dir_ovton/x.csv"), ovton::core::DataError);
}

TEST(UpdateVelocity, CentralDifferenceIsCentredAndSkipsTheObservation) {
  // Image motion x(t) = a + b t + c t²: the central difference is exact at t_k for equal intervals, the backward
  // difference (eq. 2) is half a frame late. The central value must not depend on observation k's own position.
  ovton::core::FeatureDatabase db;
  const double a = 0.1, b = 0.8, c = 3.0;
  for (int k = 0; k < 5; ++k) {
    const double t = 0.05 * k;
    const Eigen::Vector2d xy(a + b * t + c * t * t, -0.2);
    db.add_observation(7, 1000000000LL + 50000000LL * k, 458.0 * xy, xy);
  }
  const ovton::core::Feature &f = *db.get(7);
  CentralVelocityProvider central;
  VelocityProvider backward;
  Eigen::Vector2d vc, vb;
  int src = 0;
  ASSERT_TRUE(central.velocity(f, 2, vc, src));
  ASSERT_TRUE(backward.velocity(f, 2, vb, src));
  const double truth = b + 2 * c * 0.10;
  EXPECT_NEAR(vc.x(), truth, 1e-9);
  EXPECT_GT(std::abs(vb.x() - truth), 0.1);
  EXPECT_FALSE(central.velocity(f, 0, vc, src)) << "a first observation has no velocity";
  ASSERT_TRUE(central.velocity(f, 4, vc, src)); // newest: falls back to the backward difference
  EXPECT_NEAR(vc.x(), f.obs[4].vel_xy.x(), 1e-12);
  // sir_first_velocity: next — the first observation takes the second's (backward) velocity, the others keep theirs.
  const NextForFirstVelocityProvider next(backward);
  ASSERT_TRUE(next.velocity(f, 0, vb, src));
  EXPECT_EQ(src, kVelocityTracked);
  EXPECT_NEAR(vb.x(), f.obs[1].vel_xy.x(), 1e-12);
  ASSERT_TRUE(next.velocity(f, 3, vb, src));
  EXPECT_NEAR(vb.x(), f.obs[3].vel_xy.x(), 1e-12);
  ovton::core::FeatureDatabase single;
  single.add_observation(9, 1000000000LL, Eigen::Vector2d(100, 100), Eigen::Vector2d(0.1, 0.1));
  EXPECT_FALSE(next.velocity(*single.get(9), 0, vb, src)) << "a lone observation has nothing to borrow";
}
