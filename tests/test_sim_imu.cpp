// IMU consistency: integrating the noise-free synthetic IMU from the true initial state must reproduce the
// trajectory (1 cm, 0.1 deg after 10 s). Catches any sign, frame or gravity mistake in the synthesis.
#include "ov_core/io/trajectory_io.h"
#include "ov_sim/euroc_calib.h"
#include "ov_sim/imu_synth.h"
#include "ov_sim/trajectory.h"
#include "test_util.h"

#include <cmath>

using namespace ovton::core;
using namespace ovton::sim;

namespace {

struct Err {
  double pos_m = 0.0, rot_deg = 0.0;
};

Eigen::Quaterniond dq(const Eigen::Quaterniond &q, const Eigen::Vector3d &w) {
  const Eigen::Quaterniond d = q * Eigen::Quaterniond(0.0, w.x(), w.y(), w.z());
  return Eigen::Quaterniond(0.5 * d.w(), 0.5 * d.x(), 0.5 * d.y(), 0.5 * d.z());
}
Eigen::Quaterniond add(const Eigen::Quaterniond &q, const Eigen::Quaterniond &d, double h) {
  return Eigen::Quaterniond(q.w() + h * d.w(), q.x() + h * d.x(), q.y() + h * d.y(), q.z() + h * d.z());
}

/// RK4 on (q, p, v); mid-step IMU values from cubic (4-point) interpolation of the 200 Hz samples, so the
/// integrator's own error stays far below the tolerance.
Err integrate_and_compare(const Trajectory &traj, double seconds) {
  ImuSynthOptions o;
  o.calib = euroc_imu0_calib();
  o.add_noise = false;
  o.add_bias_walk = false;
  const ImuSynthResult r = synthesize_imu(traj, o);
  const auto &m = r.imu;
  const int n = static_cast<int>(m.size());
  const auto raw = [&](int i, bool gyro) -> Eigen::Vector3d { return gyro ? m[i].wm : m[i].am; };
  const auto at = [&](int i, bool gyro) -> Eigen::Vector3d {
    if (i < 0) // quadratic extrapolation at the ends
      return 3.0 * raw(0, gyro) - 3.0 * raw(1, gyro) + raw(2, gyro);
    if (i >= n)
      return 3.0 * raw(n - 1, gyro) - 3.0 * raw(n - 2, gyro) + raw(n - 3, gyro);
    return raw(i, gyro);
  };
  const Eigen::Vector3d g(0, 0, -9.81);
  const TrajectorySample s0 = traj.sample(m[0].t_imu_ns);
  Eigen::Quaterniond q = s0.q_WB;
  Eigen::Vector3d p = s0.p_W, v = s0.v_W;
  Err err;
  for (int k = 0; k + 1 < n; ++k) {
    const double h = ns_to_s(m[k + 1].t_imu_ns - m[k].t_imu_ns);
    if (ns_to_s(m[k + 1].t_imu_ns - m[0].t_imu_ns) > seconds + 1e-9)
      break;
    Eigen::Vector3d w[3], a[3];
    for (int b = 0; b < 2; ++b) {
      const bool gyro = b == 0;
      Eigen::Vector3d *dst = gyro ? w : a;
      dst[0] = at(k, gyro);
      dst[2] = at(k + 1, gyro);
      dst[1] = (-at(k - 1, gyro) + 9.0 * at(k, gyro) + 9.0 * at(k + 1, gyro) - at(k + 2, gyro)) / 16.0;
    }
    const auto acc = [&](const Eigen::Quaterniond &qq, const Eigen::Vector3d &am) {
      return Eigen::Vector3d(qq.normalized() * am + g);
    };
    const Eigen::Quaterniond k1q = dq(q, w[0]);
    const Eigen::Vector3d k1v = acc(q, a[0]), k1p = v;
    const Eigen::Quaterniond q2 = add(q, k1q, h / 2);
    const Eigen::Quaterniond k2q = dq(q2, w[1]);
    const Eigen::Vector3d k2v = acc(q2, a[1]), k2p = v + h / 2 * k1v;
    const Eigen::Quaterniond q3 = add(q, k2q, h / 2);
    const Eigen::Quaterniond k3q = dq(q3, w[1]);
    const Eigen::Vector3d k3v = acc(q3, a[1]), k3p = v + h / 2 * k2v;
    const Eigen::Quaterniond q4 = add(q, k3q, h);
    const Eigen::Quaterniond k4q = dq(q4, w[2]);
    const Eigen::Vector3d k4v = acc(q4, a[2]), k4p = v + h * k3v;
    q = Eigen::Quaterniond(q.w() + h / 6 * (k1q.w() + 2 * k2q.w() + 2 * k3q.w() + k4q.w()),
                           q.x() + h / 6 * (k1q.x() + 2 * k2q.x() + 2 * k3q.x() + k4q.x()),
                           q.y() + h / 6 * (k1q.y() + 2 * k2q.y() + 2 * k3q.y() + k4q.y()),
                           q.z() + h / 6 * (k1q.z() + 2 * k2q.z() + 2 * k3q.z() + k4q.z()))
            .normalized();
    p += h / 6 * (k1p + 2 * k2p + 2 * k3p + k4p);
    v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    const StateSample &gt = r.truth[k + 1];
    err.pos_m = std::max(err.pos_m, (p - gt.p).norm());
    err.rot_deg = std::max(err.rot_deg, Eigen::AngleAxisd(gt.q_WB.inverse() * q).angle() * 180.0 / M_PI);
  }
  return err;
}

} // namespace

TEST(SimImu, NoiseFreeImuReproducesBuiltinTrajectory) {
  LissajousTrajectory traj(10.5);
  const Err e = integrate_and_compare(traj, 10.0);
  std::cout << "[ measured ] builtin: max position error " << e.pos_m * 1e3 << " mm, rotation " << e.rot_deg
            << " deg over 10 s\n";
  EXPECT_LT(e.pos_m, 0.01);
  EXPECT_LT(e.rot_deg, 0.1);
}

TEST(SimImu, NoiseFreeImuReproducesSplineFitOfV103) {
  OVTEST_REQUIRE_SHARED_DATA();
  const std::string file = ovtest::shared_data() + "/euroc_groundtruth/V1_03_difficult.txt";
  const auto gt = read_trajectory(file);
  const int64_t t0 = gt.front().t_ns + s_to_ns(40.0); // mid-flight, the aggressive part
  SplineTrajectory traj(gt, t0, t0 + s_to_ns(10.5), 0.1, file);
  const Err e = integrate_and_compare(traj, 10.0);
  std::cout << "[ measured ] V1_03 fit: max position error " << e.pos_m * 1e3 << " mm, rotation " << e.rot_deg
            << " deg over 10 s\n";
  EXPECT_LT(e.pos_m, 0.01);
  EXPECT_LT(e.rot_deg, 0.1);
  // The fit must follow the real trajectory (it smooths mocap jitter, not the motion).
  double worst = 0.0;
  for (const auto &s : gt)
    if (s.t_ns >= t0 && s.t_ns <= t0 + s_to_ns(10.0))
      worst = std::max(worst, (traj.sample(s.t_ns).p_W - s.p).norm());
  std::cout << "[ measured ] V1_03 fit: max deviation from the ground truth " << worst * 1e3 << " mm\n";
  EXPECT_LT(worst, 0.03);
}

TEST(SimImu, NoiseLevelsFollowTheContinuousDensities) {
  LissajousTrajectory traj(50.0);
  ImuSynthOptions o;
  o.calib = euroc_imu0_calib();
  o.add_bias_walk = false;
  o.seed = 7;
  const ImuSynthResult noisy = synthesize_imu(traj, o);
  o.add_noise = false;
  const ImuSynthResult clean = synthesize_imu(traj, o);
  double sg = 0, sa = 0;
  for (size_t i = 0; i < noisy.imu.size(); ++i) {
    sg += (noisy.imu[i].wm - clean.imu[i].wm).squaredNorm();
    sa += (noisy.imu[i].am - clean.imu[i].am).squaredNorm();
  }
  sg = std::sqrt(sg / (3.0 * noisy.imu.size()));
  sa = std::sqrt(sa / (3.0 * noisy.imu.size()));
  EXPECT_NEAR(sg, o.calib.gyro_noise_density * std::sqrt(200.0), 0.05 * sg);
  EXPECT_NEAR(sa, o.calib.accel_noise_density * std::sqrt(200.0), 0.05 * sa);
  // Still: specific force is +g along the body's world-up axis.
  const TrajectorySample s = traj.sample(traj.t_begin_ns());
  const ImuData ideal = ideal_imu(s, 0, Eigen::Vector3d(0, 0, -9.81));
  EXPECT_NEAR((s.q_WB * ideal.am - s.a_W).z(), 9.81, 1e-9);
}

// Issue 16's planted IMU errors: the gyro reads (1 + s)·(I + M_g)·ω and the accelerometer (I + M_a)·f, exactly (no
// noise), and the truth's biases stay untouched.
TEST(SimImu, PlantedScaleAndMisalignmentMultiplyTheTrueReadings) {
  LissajousTrajectory traj(2.0, LissajousTrajectory::kDefaultBeginNs, 1.0);
  ImuSynthOptions o;
  o.calib = euroc_imu0_calib();
  o.add_noise = o.add_bias_walk = false;
  const ImuSynthResult ref = synthesize_imu(traj, o);
  o.gyro_scale = 0.01;
  o.gyro_M << 0.0, 0.002, 0.0, 0.002, 0.0, 0.0, 0.0, 0.0, 0.03;
  o.accel_M = Eigen::Vector3d(0.03, -0.02, 0.01).asDiagonal();
  const ImuSynthResult r = synthesize_imu(traj, o);
  ASSERT_EQ(r.imu.size(), ref.imu.size());
  const Eigen::Matrix3d G = 1.01 * (Eigen::Matrix3d::Identity() + o.gyro_M),
                        A = Eigen::Matrix3d::Identity() + o.accel_M;
  for (size_t i = 0; i < r.imu.size(); i += 37) {
    EXPECT_LT((r.imu[i].wm - G * ref.imu[i].wm).norm(), 1e-12);
    EXPECT_LT((r.imu[i].am - A * ref.imu[i].am).norm(), 1e-12);
    EXPECT_EQ(r.truth[i].bg, ref.truth[i].bg);
  }
}
