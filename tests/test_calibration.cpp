// Online calibration (calibration.* options): the measurement Jacobians w.r.t. the camera–IMU extrinsics, the
// intrinsics and the rolling-shutter readout, and the propagation's w.r.t. the IMU scale and misalignment, each against
// finite differences in the state's ⊞ convention (state.h); the IMU block's covariance propagation with them; and a
// whole run with every calibration on staying consistent.
#include "fd_check.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/replay.h"
#include "ov_core/math/so3.h"
#include "ov_eval/nees.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_msckf_ton/state/propagator.h"
#include "ov_msckf_ton/state/state_helper.h"
#include "ov_msckf_ton/update/feature_jacobians.h"
#include "ov_msckf_ton/update/updater_msckf.h"
#include "ov_sim/euroc_calib.h"
#include "ov_sim/simulator.h"
#include "test_util.h"

#include <random>

using namespace ov_msckf_ton;

namespace {

constexpr int64_t kT0 = 1403636579763555584;

/// Five clones along an arc looking at a point, calibration variables in the state, a feature with velocities.
struct CalibScene {
  ov_core::CameraCalib calib = ov_sim::euroc_cam0_calib();
  ov_core::CameraModel cam{calib};
  State state{true};
  ov_core::Feature feature;
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
      state.imu.R = ov_core::so3_exp(Eigen::Vector3d(0.03 * k, -0.02 * k, 0.04 * k)) * look;
      state.imu.p = Eigen::Vector3d(-3.0, 0.15 * k, 0.05 * k);
      state.t_imu_ns = kT0 + 50000000LL * k;
      state_helper::clone(state, state.t_imu_ns, false, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
      CloneState &cl = state.clones.rbegin()->second;
      cl.has_fej = false; // Jacobians at the current estimate, so finite differences of the residual match them
      cl.td_ref = 0.001 * k;
      Eigen::Vector2d xy;
      EXPECT_TRUE(project_in_clone(cl.R, cl.p, c.R_BC, c.p_BC, p_f, xy));
      ov_core::FeatureObservation o;
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

TEST(CalibrationJacobians, FeatureMeasurementMatchesFiniteDifferences) {
  CalibScene sc;
  UpdaterMSCKF updater(sc.calib);
  VelocityProvider tracked;
  // The first observation has no velocity: give every one a velocity so that the t_d and readout columns exist.
  NextForFirstVelocityProvider vel(tracked);
  FeatureLinearization lin;
  ASSERT_TRUE(updater.linearize(sc.state, sc.feature, sc.p_f, TdObservation::ImagePlane, vel, lin));
  ASSERT_EQ(lin.cols.size(), 6u * 5 + 1 + 6 + 8 + 1);
  const auto residual = [&](const State &s) {
    FeatureLinearization l;
    EXPECT_TRUE(updater.linearize(s, sc.feature, sc.p_f, TdObservation::ImagePlane, vel, l));
    return Eigen::VectorXd(l.r);
  };
  // r = z − h: the Jacobian of h is −∂r/∂δx.
  const Eigen::MatrixXd J = -ovtest::numeric_jacobian(residual, sc.state, sc.state.dim(), plus, 1e-7);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(lin.r.size(), sc.state.dim());
  for (size_t j = 0; j < lin.cols.size(); ++j)
    H.col(lin.cols[j]) += lin.H_x.col(static_cast<Eigen::Index>(j));
  const double scale = H.cwiseAbs().maxCoeff();
  for (int c = 0; c < sc.state.dim(); ++c) {
    const double tol = 1e-5 * scale;
    EXPECT_LT((H.col(c) - J.col(c)).cwiseAbs().maxCoeff(), tol)
        << "column " << c << "\nanalytic " << H.col(c).transpose() << "\nnumeric  " << J.col(c).transpose();
  }
}

TEST(CalibrationJacobians, ImuStepWithScaleAndMisalignmentMatchesFiniteDifferences) {
  ImuState x;
  x.R = ov_core::so3_exp(Eigen::Vector3d(0.2, -0.1, 0.3));
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
    e << ov_core::so3_log(a.R * y.R.transpose()), a.p - y.p, a.v - y.v, a.bg - y.bg, a.ba - y.ba;
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
    z.R = ov_core::so3_exp(Eigen::Vector3d(d.segment<3>(0))) * z.R;
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
  ov_sim::SimOptions so;
  so.out_dir = tmp / "sim";
  so.duration_s = 12.0;
  so.seed = 6;
  so.agility = 1.0;
  so.features_only = true;
  so.features.pixel_noise = 0.5;
  ov_sim::write_simulation(so);
  const ov_core::Dataset data = ov_core::load_dataset(so.out_dir);
  VioOptions opt;
  opt.td.mode = TdMode::Sr;
  opt.init.mode = InitMode::GroundTruth;
  opt.update.sigma_px = 0.5;
  opt.calibration.extrinsics = opt.calibration.intrinsics = opt.calibration.readout = true;
  opt.calibration.imu_intrinsics = true;
  VioManager vio(opt, data.cam, data.imu_calib);
  vio.set_groundtruth(data.groundtruth);
  ov_eval::NeesAccumulator nees(data.groundtruth, data.td_truth);
  vio.set_state_callback([&](const ov_core::StateSample &s) { nees.add(s); });
  ov_core::Replay(data).run(vio);
  const State &s = vio.state();
  const CalibState &c = s.calib;
  const auto sigma = [&](int i) { return std::sqrt(s.P(i, i)); };
  const Eigen::Vector3d e_rot = ov_core::so3_log(c.R_BC * data.cam.T_BC.topLeftCorner<3, 3>().transpose());
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
