// Online calibration (calibration.* options): the measurement Jacobians w.r.t. the camera–IMU extrinsics, the
// intrinsics and the rolling-shutter readout, and the propagation's w.r.t. the IMU scale and misalignment, each against
// finite differences in the state's ⊞ convention (state.h); the IMU block's covariance propagation with them; and a
// whole run with every calibration on staying consistent.
#include "estimator_test_util.h"
#include "fd_check.h"
#include "ov_core/io/dataset.h"
#include "ov_core/math/so3.h"
#include "ov_eval/nees.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_msckf_ton/state/propagator.h"
#include "ov_msckf_ton/state/state_helper.h"
#include "ov_msckf_ton/update/feature_jacobians.h"
#include "ov_msckf_ton/update/updater_msckf.h"
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

/// Five clones along an arc looking at a point, calibration variables in the state, a feature with velocities.
struct CalibScene {
  ovton::core::CameraCalib calib = ovton::sim::euroc_cam0_calib();
  ovton::core::CameraModel cam{calib};
  State state{true};
  ovton::core::Feature feature;
  Eigen::Vector3d p_f{0.2, -0.3, 0.1};

  CalibScene() {
    state.P = Eigen::MatrixXd::Identity(state.dim(), state.dim()) * 1e-6;
    CalibState &c = state.calib;
    c.R_BC = calib.T_BC.topLeftCorner<3, 3>();
    c.p_BC = calib.T_BC.topRightCorner<3, 1>();
    c.intrinsics << calib.intrinsics, calib.dist_coeffs;
    c.readout_s = 0.02;
    c.extrinsics_index = state.add_variable(Eigen::MatrixXd::Identity(6, 6) * 1e-4);
    c.intrinsics_index = state.add_variable(Eigen::MatrixXd::Identity(8, 8) * 1e-4);
    c.readout_index = state.add_variable(Eigen::MatrixXd::Identity(1, 1) * 1e-4);
    const Eigen::Matrix3d look = (Eigen::Matrix3d() << 0, 0, 1, -1, 0, 0, 0, -1, 0).finished() * c.R_BC.transpose();
    for (int k = 0; k < 5; ++k) {
      state.imu.R = ovton::core::so3_exp(Eigen::Vector3d(0.03 * k, -0.02 * k, 0.04 * k)) * look;
      state.imu.p = Eigen::Vector3d(-3.0, 0.15 * k, 0.05 * k);
      state.t_imu_ns = kT0 + 50000000LL * k;
      // A turning, moving body: the rolling shutter's predicted velocities (and their Jacobians) are not zero.
      state_helper::clone(state, state.t_imu_ns, false, Eigen::Vector3d(0.4, -0.9, 0.6),
                          Eigen::Vector3d(0.3, 0.8, -0.2));
      CloneState &cl = state.clones.rbegin()->second;
      cl.has_fej = false; // Jacobians at the current estimate, so finite differences of the residual match them
      cl.td_ref = 0.001 * k;
      Eigen::Vector2d xy;
      EXPECT_TRUE(project_in_clone(cl.R, cl.p, c.R_BC, c.p_BC, p_f, xy));
      ovton::core::FeatureObservation o;
      o.t_cam_ns = state.t_imu_ns;
      o.uv = cam.distort(xy) + Eigen::Vector2d(0.3 * k, -0.2 * k); // off the model, so residuals are not zero
      o.xy = cam.undistort(o.uv);
      if (!feature.obs.empty()) {
        o.vel_xy = (o.xy - feature.obs.back().xy) / 0.05;
        o.vel_valid = true;
      }
      feature.obs.push_back(o);
    }
    state.td = 0.004;
  }
};

/// The state perturbed by δ (⊞): every variable, calibration included.
State plus(const State &s, const Eigen::VectorXd &d) {
  State t = s;
  t.boxplus(d);
  return t;
}

} // namespace

/// Compares a measurement's analytic Jacobian (compact columns `cols`) with the finite differences of its residual
/// over the whole state; r = z − h, so the Jacobian of h is −∂r/∂δx.
template <typename Residual>
void expect_matches_finite_differences(const State &state, const Eigen::MatrixXd &H_compact,
                                       const std::vector<int> &cols, const Residual &residual) {
  const Eigen::MatrixXd J = -ovtest::numeric_jacobian(residual, state, state.dim(), plus, 1e-7);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(H_compact.rows(), state.dim());
  for (size_t j = 0; j < cols.size(); ++j)
    H.col(cols[j]) += H_compact.col(static_cast<Eigen::Index>(j));
  const double tol = 1e-5 * H.cwiseAbs().maxCoeff();
  for (int c = 0; c < state.dim(); ++c)
    EXPECT_LT((H.col(c) - J.col(c)).cwiseAbs().maxCoeff(), tol)
        << "column " << c << "\nanalytic " << H.col(c).transpose() << "\nnumeric  " << J.col(c).transpose();
}

TEST(CalibrationJacobians, FeatureMeasurementMatchesFiniteDifferences) {
  // The readout's row shift with the velocity the state predicts (default) and with the tracked one.
  for (const bool state_velocity : {true, false}) {
    SCOPED_TRACE(state_velocity ? "state velocity" : "tracked velocity");
    CalibScene sc;
    UpdaterMSCKFOptions opt;
    opt.readout_state_velocity = state_velocity;
    UpdaterMSCKF updater(sc.calib, opt);
    VelocityProvider tracked;
    // The first observation has no velocity: give every one a velocity so that the t_d and readout columns exist.
    NextForFirstVelocityProvider vel(tracked);
    FeatureLinearization lin;
    ASSERT_TRUE(updater.linearize(sc.state, sc.feature, sc.p_f, TdObservation::ImagePlane, vel, lin));
    ASSERT_EQ(lin.cols.size(), 6u * 5 + 1 + 6 + 8 + 1);
    expect_matches_finite_differences(sc.state, lin.H_x, lin.cols, [&](const State &s) {
      FeatureLinearization l;
      EXPECT_TRUE(updater.linearize(s, sc.feature, sc.p_f, TdObservation::ImagePlane, vel, l));
      return Eigen::VectorXd(l.r);
    });
    // H_f too (the feature's nullspace projection removes exactly its column space).
    const auto of_point = [&](const Eigen::Vector3d &p) {
      FeatureLinearization l;
      EXPECT_TRUE(updater.linearize(sc.state, sc.feature, p, TdObservation::ImagePlane, vel, l));
      return Eigen::VectorXd(l.r);
    };
    const Eigen::MatrixXd Hf_fd = -ovtest::numeric_jacobian(of_point, sc.p_f, 1e-7);
    EXPECT_LT((lin.H_f - Hf_fd).cwiseAbs().maxCoeff(), 1e-5 * lin.H_f.cwiseAbs().maxCoeff()) << "analytic\n"
                                                                                             << lin.H_f << "\nnumeric\n"
                                                                                             << Hf_fd;
  }
}

TEST(CalibrationJacobians, LandmarkMeasurementWithReadoutMatchesFiniteDifferences) {
  // A landmark updated by the newest observation, every calibration block and the readout's predicted velocity on.
  CalibScene sc;
  UpdaterMSCKF msckf(sc.calib);
  UpdaterSLAM slam(sc.calib, UpdaterSlamOptions(), msckf);
  LandmarkState l;
  l.id = sc.feature.id;
  l.p_W = l.p_fej = sc.p_f + Eigen::Vector3d(0.01, -0.02, 0.015);
  l.index = sc.state.add_variable(Eigen::Matrix3d::Identity() * 1e-4);
  sc.state.landmarks[l.id] = l;
  const VelocityProvider tracked;
  const size_t k = sc.feature.obs.size() - 1;
  const auto lin_at = [&](const State &s, LandmarkLinearization &out) {
    return slam.linearize(s, s.landmarks.at(l.id), s.clones.rbegin()->second, sc.feature, k,
                          TdObservation::StateRelevant, tracked, out);
  };
  LandmarkLinearization lin;
  ASSERT_TRUE(lin_at(sc.state, lin));
  ASSERT_EQ(lin.calib_cols.size(), 6u + 8 + 1);
  Eigen::MatrixXd H(2, 6 + 3 + lin.calib_cols.size());
  H << lin.H_clone, lin.H_f, lin.H_calib;
  std::vector<int> cols;
  for (int j = 0; j < 6; ++j)
    cols.push_back(sc.state.clones.rbegin()->second.index + j);
  for (int j = 0; j < 3; ++j)
    cols.push_back(l.index + j);
  cols.insert(cols.end(), lin.calib_cols.begin(), lin.calib_cols.end());
  expect_matches_finite_differences(sc.state, H, cols, [&](const State &s) {
    State t = s;
    LandmarkState &tl = t.landmarks.at(l.id);
    tl.p_fej = tl.p_W; // Jacobians at the current estimate
    LandmarkLinearization out;
    EXPECT_TRUE(lin_at(t, out));
    return Eigen::VectorXd(out.r);
  });
}

TEST(CalibrationJacobians, ImuStepWithScaleAndMisalignmentMatchesFiniteDifferences) {
  ImuState x;
  x.R = ovton::core::so3_exp(Eigen::Vector3d(0.2, -0.1, 0.3));
  x.v = Eigen::Vector3d(0.4, -0.2, 0.1);
  x.p = Eigen::Vector3d(1, 2, 3);
  x.bg = Eigen::Vector3d(0.01, -0.02, 0.015);
  x.ba = Eigen::Vector3d(0.1, 0.05, -0.08);
  x.set_fej();
  ImuIntrinsics D;
  D.D_w << 1.01, 0, 0, 0.003, 0.99, 0, -0.002, 0.004, 1.02;
  D.D_a << 0.98, 0, 0, 0.005, 1.01, 0, 0.001, -0.003, 1.03;
  const Eigen::Vector3d wm(0.5, -0.8, 1.1), am(0.3, 0.4, 9.7), g(0, 0, -9.81);
  const double dt = 0.005;
  ImuNoise noise;
  ImuState y;
  Mat15 Phi, Q;
  Mat15x12 G;
  imu_step_calibrated(x, D, wm, am, dt, g, noise, y, &Phi, &Q, &G);
  // The step's error as a 15-vector in the state convention.
  const auto err = [&](const ImuState &a) {
    Eigen::Matrix<double, 15, 1> e;
    e << ovton::core::so3_log(a.R * y.R.transpose()), a.p - y.p, a.v - y.v, a.bg - y.bg, a.ba - y.ba;
    return e;
  };
  const auto step_from_intrinsics = [&](const Eigen::VectorXd &d) {
    ImuIntrinsics E = D;
    for (int k = 0; k < 6; ++k) {
      E.D_w(kTriRow[k], kTriCol[k]) += d(k);
      E.D_a(kTriRow[k], kTriCol[k]) += d(6 + k);
    }
    ImuState z;
    imu_step_calibrated(x, E, wm, am, dt, g, noise, z, nullptr, nullptr, nullptr);
    return Eigen::VectorXd(err(z));
  };
  const Eigen::MatrixXd G_fd =
      ovtest::numeric_jacobian(step_from_intrinsics, Eigen::VectorXd(Eigen::VectorXd::Zero(12)), 1e-6);
  EXPECT_LT((G - G_fd).cwiseAbs().maxCoeff(), 1e-6 * G.cwiseAbs().maxCoeff() + 1e-12) << "analytic\n"
                                                                                      << G << "\nnumeric\n"
                                                                                      << G_fd;
  // The state columns with D != I (the bias columns carry D).
  const auto step_from_state = [&](const Eigen::VectorXd &d) {
    ImuState z = x;
    z.R = ovton::core::so3_exp(Eigen::Vector3d(d.segment<3>(0))) * z.R;
    z.p += d.segment<3>(3);
    z.v += d.segment<3>(6);
    z.bg += d.segment<3>(9);
    z.ba += d.segment<3>(12);
    z.set_fej();
    ImuState w;
    imu_step_calibrated(z, D, wm, am, dt, g, noise, w, nullptr, nullptr, nullptr);
    return Eigen::VectorXd(err(w));
  };
  const Eigen::MatrixXd F_fd =
      ovtest::numeric_jacobian(step_from_state, Eigen::VectorXd(Eigen::VectorXd::Zero(15)), 1e-6);
  EXPECT_LT((Phi - F_fd).cwiseAbs().maxCoeff(), 1e-6) << "analytic\n" << Phi << "\nnumeric\n" << F_fd;
}

TEST(CalibrationPropagation, CovarianceWithIntrinsicsIsAPAtPlusQ) {
  std::mt19937 rng(2);
  std::normal_distribution<double> n(0, 1);
  State s(true);
  s.calib.imu_intrinsics_index = s.add_variable(Eigen::MatrixXd::Identity(12, 12) * 1e-4);
  s.add_variable(Eigen::MatrixXd::Identity(6, 6)); // something behind, like a clone
  Eigen::MatrixXd A0(s.dim(), s.dim());
  for (int i = 0; i < A0.size(); ++i)
    A0(i) = n(rng);
  s.P = A0 * A0.transpose();
  const Eigen::MatrixXd P0 = s.P;
  Mat15 Phi, Q;
  Mat15x12 G;
  for (int i = 0; i < Phi.size(); ++i)
    Phi(i) = n(rng);
  for (int i = 0; i < G.size(); ++i)
    G(i) = n(rng);
  Q = Mat15::Identity() * 0.1;
  state_helper::propagate_covariance(s, Phi, Q, G, s.calib.imu_intrinsics_index);
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(s.dim(), s.dim());
  A.topLeftCorner<15, 15>() = Phi;
  A.block(0, s.calib.imu_intrinsics_index, 15, 12) = G;
  Eigen::MatrixXd expected = A * P0 * A.transpose();
  expected.topLeftCorner<15, 15>() += Q;
  EXPECT_LT((s.P - expected).cwiseAbs().maxCoeff(), 1e-9 * expected.cwiseAbs().maxCoeff());
}

TEST(CalibrationRun, EveryCalibrationOnStaysConsistentOnCleanData) {
  // A feature-level flight whose calibration is exactly what the dataset says: with every calibration estimated,
  // the pose stays consistent and no calibration wanders beyond its sigma.
  ovtest::TempDir tmp;
  const ovton::core::Dataset data = ovtest::feature_flight(tmp / "sim", 12.0, 6, 0.5, 1.0);
  VioOptions opt = ovtest::gt_run_options(TdMode::Sr, 0.5);
  opt.calibration.extrinsics = opt.calibration.intrinsics = opt.calibration.readout = true;
  opt.calibration.imu_intrinsics = true;
  std::optional<State> last;
  const auto run = ovtest::run_estimator(data, opt, {ovtest::peek([&](const VioManager &f) { last = f.state(); })});
  ovton::eval::NeesAccumulator nees(data.groundtruth, data.td_truth);
  for (const auto &st : run.traj)
    nees.add(st);
  ASSERT_TRUE(last);
  const State &s = *last;
  const CalibState &c = s.calib;
  const auto sigma = [&](int i) { return std::sqrt(s.P(i, i)); };
  const Eigen::Vector3d e_rot = ovton::core::so3_log(c.R_BC * data.cam.T_BC.topLeftCorner<3, 3>().transpose());
  std::cout << "[calibration] NEES orientation " << nees.stats().ori() << ", position " << nees.stats().pos()
            << "; extrinsic rotation error " << e_rot.norm() * 180 / M_PI << " deg (sigma "
            << sigma(c.extrinsics_index) * 180 / M_PI << "), fu " << c.intrinsics(0) << " (true "
            << data.cam.intrinsics(0) << ", sigma " << sigma(c.intrinsics_index) << "), readout " << c.readout_s * 1e3
            << " ms (sigma " << sigma(c.readout_index) * 1e3 << "), D_w(0,0) " << c.D_w(0, 0) << " (sigma "
            << sigma(c.imu_intrinsics_index) << ")\n";
  EXPECT_LT(nees.stats().ori(), 6.0);
  EXPECT_LT(nees.stats().pos(), 6.0);
  for (int k = 0; k < 3; ++k) {
    EXPECT_LT(std::abs(e_rot(k)), 4 * sigma(c.extrinsics_index + k));
  }
  EXPECT_LT(std::abs(c.intrinsics(0) - data.cam.intrinsics(0)), 4 * sigma(c.intrinsics_index));
  EXPECT_LT(std::abs(c.readout_s), 4 * sigma(c.readout_index));
  EXPECT_LT(std::abs(c.D_w(0, 0) - 1.0), 4 * sigma(c.imu_intrinsics_index));
}
