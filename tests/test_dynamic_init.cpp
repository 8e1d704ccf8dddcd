// Dynamic initialisation (ov_msckf_ton/init): pre-integration against the trajectory it integrates, the window solver
// on synthetic tracks with known biases, `auto` telling still from moving, and the real moving EuRoC cut without ground
// truth against the ground-truth start.
#include "estimator_test_util.h"
#include "ov_core/cam/camera_model.h"
#include "ov_core/io/dataset.h"
#include "ov_core/math/so3.h"
#include "ov_eval/init_check.h"
#include "ov_eval/metrics.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_msckf_ton/init/dynamic_init.h"
#include "ov_sim/euroc_calib.h"
#include "ov_sim/imu_synth.h"
#include "ov_sim/trajectory.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace ovton::msckf;
using ovton::core::ImuData;

namespace {

const Eigen::Vector3d kGravity(0, 0, -9.81);

double rad2deg(double r) {
  return r * 180.0 / M_PI;
}

/// Roll/pitch and velocity errors as `ovton run` reports them (ov_eval/init_check.h), for a state and its truth.
ovton::eval::InitCheck check(const Eigen::Matrix3d &R, const Eigen::Vector3d &v,
                             const ovton::sim::TrajectorySample &truth, int64_t t_ns) {
  ovton::core::StateSample est, gt;
  est.t_ns = gt.t_ns = t_ns;
  est.q_WB = Eigen::Quaterniond(R);
  est.v = v;
  gt.q_WB = truth.q_WB;
  gt.v = truth.v_W;
  gt.has_velocity = true;
  return ovton::eval::check_initialisation(est, {gt, gt}, t_ns);
}

std::deque<ImuData> ideal_imu_log(const ovton::sim::Trajectory &traj, int64_t t0, int64_t t1, const Eigen::Vector3d &bg,
                                  const Eigen::Vector3d &ba) {
  std::deque<ImuData> imu;
  for (int64_t t = t0; t <= t1; t += 5000000) {
    ImuData d = ovton::sim::ideal_imu(traj.sample(t), t, kGravity);
    d.wm += bg;
    d.am += ba;
    imu.push_back(d);
  }
  return imu;
}

} // namespace

TEST(Preintegration, MatchesTheTrajectory) {
  ovton::sim::LissajousTrajectory traj(20.0, 1000000000LL, 1.0);
  const int64_t t0 = traj.t_begin_ns() + 2000000000LL, t1 = t0 + 1000000000LL;
  const Eigen::Vector3d bg(0.01, -0.02, 0.03), ba(0.1, -0.05, 0.08);
  const auto imu = ideal_imu_log(traj, t0 - 100000000LL, t1 + 100000000LL, bg, ba);
  std::vector<Preintegrated> pre;
  ASSERT_TRUE(preintegrate(imu, t0 + 1234567, {t0 + 1234567, t1 - 777}, bg, ba, pre));
  const auto a = traj.sample(t0 + 1234567), b = traj.sample(t1 - 777);
  const Eigen::Matrix3d Ra = a.q_WB.toRotationMatrix(), Rb = b.q_WB.toRotationMatrix();
  const double T = 1e-9 * static_cast<double>((t1 - 777) - (t0 + 1234567));
  EXPECT_LT((pre[0].p).norm(), 1e-15);
  EXPECT_LT(ovton::core::so3_log(pre[1].R.transpose() * Ra.transpose() * Rb).norm(), 1e-5);
  EXPECT_LT((pre[1].v - Ra.transpose() * (b.v_W - a.v_W - kGravity * T)).norm(), 2e-4);
  EXPECT_LT((pre[1].p - Ra.transpose() * (b.p_W - a.p_W - a.v_W * T - 0.5 * kGravity * T * T)).norm(), 1e-4);
  EXPECT_FALSE(preintegrate(imu, t0, {t1 + 1000000000LL}, bg, ba, pre)); // beyond the log
}

namespace {

/// One synthetic window: 21 frames at 20 Hz of landmarks 2-6 m in front of the first camera pose along an agile
/// flight, with pixel noise, and the IMU log (with biases) around it.
struct SyntheticWindow {
  std::vector<InitFrame> frames;
  std::deque<ImuData> imu;
  ovton::sim::TrajectorySample truth; ///< at the newest frame
};

SyntheticWindow synthetic_window(const ovton::sim::Trajectory &traj, const ovton::core::CameraModel &cam,
                                 int64_t t_start, const Eigen::Vector3d &bg, const Eigen::Vector3d &ba,
                                 std::mt19937 &landmark_rng, std::mt19937 &noise_rng, double px_sigma) {
  const Eigen::Matrix4d &T_BC = cam.calib().T_BC;
  SyntheticWindow w;
  w.imu = ideal_imu_log(traj, t_start - 200000000LL, t_start + 1300000000LL, bg, ba);
  const auto s0 = traj.sample(t_start);
  const Eigen::Matrix3d R_WC0 = s0.q_WB.toRotationMatrix() * T_BC.block<3, 3>(0, 0);
  const Eigen::Vector3d p_WC0 = s0.p_W + s0.q_WB.toRotationMatrix() * T_BC.block<3, 1>(0, 3);
  std::uniform_real_distribution<double> u(-1.0, 1.0), depth(2.0, 6.0);
  std::normal_distribution<double> px_noise(0.0, px_sigma);
  std::vector<Eigen::Vector3d> lm;
  for (int i = 0; i < 200; ++i) {
    const double z = depth(landmark_rng);
    lm.push_back(p_WC0 + R_WC0 * Eigen::Vector3d(u(landmark_rng) * 0.7 * z, u(landmark_rng) * 0.45 * z, z));
  }
  for (int k = 0; k <= 20; ++k) {
    InitFrame f;
    f.t_cam_ns = f.t_imu_ns = t_start + k * 50000000LL;
    const auto s = traj.sample(f.t_imu_ns);
    const Eigen::Matrix3d R_WC = s.q_WB.toRotationMatrix() * T_BC.block<3, 3>(0, 0);
    const Eigen::Vector3d p_WC = s.p_W + s.q_WB.toRotationMatrix() * T_BC.block<3, 1>(0, 3);
    for (size_t i = 0; i < lm.size(); ++i) {
      Eigen::Vector2d uv;
      if (!cam.project(R_WC.transpose() * (lm[i] - p_WC), uv) || !cam.in_image(uv, 5))
        continue;
      uv += Eigen::Vector2d(px_noise(noise_rng), px_noise(noise_rng));
      f.obs.emplace_back(i, cam.undistort(uv));
    }
    w.frames.push_back(f);
  }
  w.truth = traj.sample(w.frames.back().t_imu_ns);
  return w;
}

/// Error of an initialisation in its own world frame, [δθ_x δθ_y δv] (state.h's convention): the truth's world is
/// first turned about z onto the estimate's, whose yaw is arbitrary.
Eigen::Matrix<double, 5, 1> tilt_velocity_error(const DynamicInitResult &r, const ovton::sim::TrajectorySample &truth) {
  const Eigen::Matrix3d R_true = truth.q_WB.toRotationMatrix();
  const Eigen::Matrix3d A = r.R_WB * R_true.transpose();
  const Eigen::Matrix3d Rz =
      Eigen::AngleAxisd(std::atan2(A(1, 0), A(0, 0)), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Eigen::Matrix<double, 5, 1> e;
  e << ovton::core::so3_log(Rz * R_true * r.R_WB.transpose()).head<2>(), Rz * truth.v_W - r.v_W;
  return e;
}

/// The same block of the covariance the initialiser computed from its information (before the hand-over inflation).
Eigen::Matrix<double, 5, 5> tilt_velocity_cov(const DynamicInitResult &r, double inflation) {
  const int idx[5] = {0, 1, 6, 7, 8};
  Eigen::Matrix<double, 5, 5> C;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j)
      C(i, j) = r.P(idx[i], idx[j]) / (inflation * inflation);
  return C;
}

} // namespace

// Tracks of random landmarks along an agile flight, with IMU biases the solver is not told: it must find the state
// of the newest frame, the biases, and a covariance that covers its error.
TEST(DynamicInit, RecoversMovingStateAndBiases) {
  ovton::sim::LissajousTrajectory traj(30.0, 1000000000LL, 1.0);
  const ovton::core::CameraModel cam(ovton::sim::euroc_cam0_calib());
  const Eigen::Matrix4d T_BC = cam.calib().T_BC;
  const Eigen::Vector3d bg(0.004, -0.02, 0.03), ba(0.05, -0.08, 0.1);
  std::mt19937 rng(7);
  int trials = 0, ok = 0;
  double worst_tilt = 0, worst_v = 0, worst_bg = 0;
  // 24 windows along the flight: with fewer, one window whose velocity sigma sits at the gate decides the rate (it
  // flips between compilers: 5 of 6 with gcc, 4 of 6 with clang).
  for (int64_t t_start = traj.t_begin_ns() + 1000000000LL; trials < 24; t_start += 1100000000LL, ++trials) {
    const SyntheticWindow w = synthetic_window(traj, cam, t_start, bg, ba, rng, rng, 0.5);
    DynamicInitOptions o;
    const DynamicInitResult r = dynamic_initialize(w.frames, w.imu, T_BC, 458.0, 9.81, 1e-4, 1e-4, 1.0, o);
    if (!r.ok) {
      std::cout << "trial " << trials << ": " << r.why << "\n";
      continue;
    }
    ++ok;
    const auto ic = check(r.R_WB, r.v_W, w.truth, w.frames.back().t_imu_ns);
    ASSERT_TRUE(ic.ok);
    const double tilt = ic.tilt_err_deg, dv = ic.vel_err_m_s;
    worst_tilt = std::max(worst_tilt, tilt);
    worst_v = std::max(worst_v, dv);
    worst_bg = std::max(worst_bg, (r.bg - bg).norm());
    // The covariance it hands over covers the error (sigmas are inflated by 2: a 3-sigma check on them is loose on
    // purpose; the NEES is measured on whole runs).
    EXPECT_LT(tilt, 3 * rad2deg(std::sqrt(r.P(0, 0) + r.P(1, 1))) + 0.05) << r.why;
    EXPECT_LT(dv, 3 * std::sqrt(r.P.block<3, 3>(6, 6).trace()) + 0.005) << r.why;
  }
  // The gate refuses windows whose tilt and velocity (b_a held) are not determined to 0.5 deg / 0.04 m/s; along this
  // agile flight it accepts 17 of 24 at f2880bc (gcc). No absolute tilt bar here: an accepted window's tilt error
  // reaches 5.1 deg on this flight (within the 3 sigma of the covariance handed to the filter, checked above); the
  // issue's 1.5 deg bar is checked on the real moving cut (DynamicInitReal) and tabulated on renderings (docs/bags.md).
  EXPECT_GE(3 * ok, 2 * trials) << "of " << trials;
  EXPECT_LT(worst_bg, 0.005);
  std::cout << ok << " of " << trials << " windows accepted; worst roll/pitch error " << worst_tilt << " deg, velocity "
            << worst_v << " m/s, b_g " << worst_bg << " rad/s\n";
}

// The covariance against the Monte-Carlo spread of the estimate: one window, many pixel-noise draws with the noise the
// solver is told. The rms roll/pitch and velocity errors must match the sigmas the information gives (before the
// hand-over inflation): the sigmas near 1 deg are the window's real spread (b_a and tilt trade off over 1 s), not an
// overestimate. The joint 5-d NEES is printed only: tilt and world velocity are nearly collinear (δv ≈ δθ × v), so
// it weighs a near-singular direction.
TEST(DynamicInit, CovarianceMatchesMonteCarloSpread) {
  ovton::sim::LissajousTrajectory traj(30.0, 1000000000LL, 1.0);
  const ovton::core::CameraModel cam(ovton::sim::euroc_cam0_calib());
  const Eigen::Vector3d bg(0.004, -0.02, 0.03), ba(0.05, -0.08, 0.1);
  DynamicInitOptions o;
  const double sigma_px = 0.5;
  o.max_sigma_rollpitch_deg = o.max_sigma_vel = 1e9; // the spread is measured, not gated
  const int64_t t_start = traj.t_begin_ns() + 3000000000LL;
  std::mt19937 noise_rng(11);
  const int runs = 40;
  double nees = 0, tilt_ms = 0, sig_tilt = 0, vel_ms = 0, sig_vel = 0;
  Eigen::Matrix<double, 5, 1> mean = Eigen::Matrix<double, 5, 1>::Zero();
  for (int i = 0; i < runs; ++i) {
    std::mt19937 landmark_rng(7); // the same scene every run
    const SyntheticWindow w = synthetic_window(traj, cam, t_start, bg, ba, landmark_rng, noise_rng, sigma_px);
    const DynamicInitResult r =
        dynamic_initialize(w.frames, w.imu, cam.calib().T_BC, 458.0, 9.81, 1e-4, 1e-4, sigma_px, o);
    ASSERT_TRUE(r.ok) << r.why;
    const auto e = tilt_velocity_error(r, w.truth);
    const auto C = tilt_velocity_cov(r, o.sigma_inflation);
    nees += e.dot(C.ldlt().solve(e)) / runs;
    mean += e / runs;
    tilt_ms += e.head<2>().squaredNorm() / runs;
    sig_tilt += (C(0, 0) + C(1, 1)) / runs;
    vel_ms += e.tail<3>().squaredNorm() / runs;
    sig_vel += C.bottomRightCorner<3, 3>().trace() / runs;
    if (i == 0)
      std::cout << r.why << "\n";
  }
  std::cout << "Monte-Carlo over " << runs << " noise draws: mean NEES " << nees << " (dim 5), rms tilt error "
            << rad2deg(std::sqrt(tilt_ms)) << " deg against sigma " << rad2deg(std::sqrt(sig_tilt))
            << " deg, rms velocity error " << std::sqrt(vel_ms) << " m/s against sigma " << std::sqrt(sig_vel)
            << " m/s; mean error " << mean.transpose() << "\n";
  const double tilt_ratio = std::sqrt(tilt_ms / sig_tilt), vel_ratio = std::sqrt(vel_ms / sig_vel);
  EXPECT_GT(tilt_ratio, 0.6);
  EXPECT_LT(tilt_ratio, 1.6);
  EXPECT_GT(vel_ratio, 0.6);
  EXPECT_LT(vel_ratio, 1.6);
}

// Too little motion: refused, not guessed.
TEST(DynamicInit, RefusesAStillWindow) {
  ovton::sim::LissajousTrajectory traj(30.0, 1000000000LL, 0.0);
  const ovton::core::CameraModel cam(ovton::sim::euroc_cam0_calib());
  const int64_t t0 = traj.t_begin_ns() + 3000000000LL;
  const auto imu =
      ideal_imu_log(traj, t0 - 200000000LL, t0 + 1300000000LL, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  std::vector<InitFrame> frames(21);
  for (int k = 0; k <= 20; ++k) {
    frames[k].t_cam_ns = frames[k].t_imu_ns = t0 + k * 50000000LL;
    for (size_t i = 0; i < 40; ++i) // the same points in every frame: no image motion at all
      frames[k].obs.emplace_back(i, Eigen::Vector2d(0.01 * static_cast<double>(i) - 0.2, 0.005 * (i % 7)));
  }
  const DynamicInitResult r =
      dynamic_initialize(frames, imu, cam.calib().T_BC, 458.0, 9.81, 1e-4, 1e-4, 1.0, DynamicInitOptions{});
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.why.find("too little image motion"), std::string::npos) << r.why;
}

namespace {

struct CutRun {
  std::vector<ovton::core::StateSample> traj;
  std::string init_message;
  long images_before_init = 0;
};

CutRun run_cut(const ovton::core::Dataset &d, InitMode mode) {
  VioOptions opt = load_vio_options(std::string(OVTON_SOURCE_DIR) + "/config/euroc_mav/estimator_config.yaml");
  opt.init.mode = mode;
  opt.td.search.enabled = false; // the initialisers and the filter, from the configured t_d
  const ovtest::EstimatorRun run = ovtest::run_estimator(d, opt);
  CutRun r;
  r.traj = run.traj;
  r.init_message = run.report.init_message;
  r.images_before_init = run.report.counters.images_before_init;
  return r;
}

} // namespace

// The bar on the real moving cut (V1_01 in flight, 4.45 s): initialised within 1.5 s of images, roll/pitch
// within 1.5 deg and velocity within 0.1 m/s of the ground truth, and the rest of the cut's APE within 2x of the run
// started from the ground truth (over the same poses).
TEST(DynamicInitReal, MovingEurocCutWithoutGroundTruth) {
  OVTEST_REQUIRE_SHARED_DATA();
  const ovton::core::Dataset d = ovton::core::load_dataset(ovtest::shared_data() + "/euroc_v1_01_moving");
  const CutRun dyn = run_cut(d, InitMode::Auto);
  ASSERT_FALSE(dyn.traj.empty()) << dyn.init_message;
  EXPECT_NE(dyn.init_message.find("dynamic initialisation"), std::string::npos) << dyn.init_message;
  const ovton::core::StateSample &first = dyn.traj.front();
  const auto ic = ovton::eval::check_initialisation(first, d.groundtruth, d.images.front().t_cam_ns);
  ASSERT_TRUE(ic.ok);
  const double data_s = ic.data_s, tilt = ic.tilt_err_deg, dv = ic.vel_err_m_s;
  EXPECT_LE(data_s, 1.5) << dyn.init_message;
  std::cout << "dynamic init after " << data_s << " s of images: roll/pitch error " << tilt << " deg, velocity error "
            << dv << " m/s (" << dyn.init_message << ")\n";
  EXPECT_LT(tilt, 1.5);
  EXPECT_LT(dv, 0.1);

  const CutRun ref = run_cut(d, InitMode::GroundTruth);
  std::vector<ovton::core::StateSample> ref_rest;
  for (const auto &s : ref.traj)
    if (s.t_ns >= first.t_ns)
      ref_rest.push_back(s);
  const auto e_dyn = ovton::eval::evaluate(dyn.traj, d.groundtruth, {}, ovton::eval::EvalOptions{});
  const auto e_ref = ovton::eval::evaluate(ref_rest, d.groundtruth, {}, ovton::eval::EvalOptions{});
  std::cout << "APE after the dynamic start " << e_dyn.ape_rmse_m << " m, ground-truth start over the same poses "
            << e_ref.ape_rmse_m << " m\n";
  EXPECT_LT(e_dyn.ape_rmse_m, 2.0 * e_ref.ape_rmse_m);
}

// auto on a still start (the micro cut stands on the ground) is the static initialisation.
TEST(DynamicInitReal, StillEurocStartIsStatic) {
  OVTEST_REQUIRE_SHARED_DATA();
  ovton::core::Dataset d = ovton::core::load_dataset(ovtest::shared_data() + "/euroc_v1_01_micro");
  d.images.resize(40);
  const CutRun r = run_cut(d, InitMode::Auto);
  ASSERT_FALSE(r.traj.empty()) << r.init_message;
  EXPECT_EQ(r.init_message.rfind("static initialisation", 0), 0u) << r.init_message;
  EXPECT_LT(r.traj.back().v.norm(), 0.05);
}
