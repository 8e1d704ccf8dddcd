// The IMU error model (ov_sim/imu_errors.h) and its measurement (ov_sim/imu_match.h): the measurement finds a
// planted ground-truth time shift and frame rotation and keeps them apart from the IMU's own errors; a synthetic log
// with the euroc model, measured the same way, shows the spectrum the model asks for; on the real V1_01 log the
// measurement agrees with EuRoC's own bias estimate and still gives the numbers the euroc preset carries.
#include "ov_core/io/dataset.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_sim/imu_errors.h"
#include "ov_sim/imu_match.h"
#include "ov_sim/imu_synth.h"
#include "ov_sim/trajectory.h"
#include "test_util.h"

#include <Eigen/Geometry>

using namespace ov_sim;

namespace {

/// Ground truth of the built-in flight at 200 Hz (pose, velocity), as a reader would return it.
std::vector<ov_core::StateSample> builtin_truth(const Trajectory &traj) {
  std::vector<ov_core::StateSample> gt;
  for (int64_t t = traj.t_begin_ns(); t <= traj.t_end_ns(); t += 5000000)
    gt.push_back(to_state_sample(traj.sample(t), t));
  return gt;
}

ImuSynthOptions noise_free_imu() {
  ImuSynthOptions io;
  io.calib.rate_hz = 200.0;
  io.add_noise = io.add_bias_walk = false;
  return io;
}

/// The EuRoC datasheet's white noise (ADIS16448); bias walk off unless asked for.
ImuSynthOptions datasheet_imu(uint64_t seed) {
  ImuSynthOptions io;
  io.calib.rate_hz = 200.0;
  io.calib.gyro_noise_density = 1.6968e-4;
  io.calib.accel_noise_density = 2.0e-3;
  io.add_bias_walk = false;
  io.seed = seed;
  return io;
}

} // namespace

TEST(SimImuMatch, FindsAPlantedGroundTruthShiftAndRotationAndTheGyroScale) {
  const LissajousTrajectory traj(60.0, LissajousTrajectory::kDefaultBeginNs, 1.0);
  ImuSynthOptions io = noise_free_imu();
  io.gyro_scale = 0.01;
  io.bg0 = Eigen::Vector3d(0.01, -0.02, 0.03);
  io.ba0 = Eigen::Vector3d(0.1, 0.0, -0.05);
  const ImuSynthResult imu = synthesize_imu(traj, io);
  // The ground truth is stamped 4 ms late and its body frame is rotated by 0.5 deg against the IMU's axes.
  const Eigen::Matrix3d R_BI = Eigen::AngleAxisd(0.5 * M_PI / 180, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  std::vector<ov_core::StateSample> gt = builtin_truth(traj);
  for (auto &s : gt) {
    s.t_ns += 4000000;
    s.q_WB = Eigen::Quaterniond(s.q_WB.toRotationMatrix() * R_BI);
  }
  const ImuMatchReport r = match_imu(imu.imu, gt);
  std::cout << "[ measured ] planted shift 4 ms -> " << r.gt_shift_s * 1e3 << " ms; rotation 0.5 deg -> "
            << r.gt_rotation.norm() * 180 / M_PI << " deg; gyro scale " << r.gyro_S.diagonal().transpose()
            << "; accel bias " << r.accel_bias.transpose() << "\n";
  EXPECT_NEAR(r.gt_shift_s, 0.004, 0.0005);
  const Eigen::Vector3d planted = Eigen::AngleAxisd(R_BI).angle() * Eigen::AngleAxisd(R_BI).axis();
  EXPECT_LT((r.gt_rotation - planted).norm(), 0.02 * M_PI / 180);
  EXPECT_NEAR(r.gyro_S(0, 0), 1.01, 1e-3);
  EXPECT_NEAR(r.gyro_S(2, 2), 1.01, 1e-3);
  EXPECT_LT((r.gyro_bias - io.bg0).norm(), 1e-4);
  EXPECT_LT((r.accel_bias - io.ba0).norm(), 5e-3);
}

TEST(SimImuErrors, ASyntheticLogShowsTheSpectrumTheModelAsksFor) {
  const LissajousTrajectory traj(150.0);
  const ImuSynthOptions io = datasheet_imu(11);
  ImuSynthResult imu = synthesize_imu(traj, io);
  const ImuErrorModel m = euroc_v1_01_imu_errors();
  add_imu_errors(traj, m, io.calib.gyro_noise_density, io.calib.accel_noise_density, 12, imu.imu, imu.truth);
  const ImuMatchReport r = match_imu(imu.imu, builtin_truth(traj));
  ASSERT_EQ(r.gyro_flight_spectrum.size(), r.accel_flight_spectrum.size());
  int checked = 0;
  for (size_t i = 0; i < r.gyro_flight_spectrum.size(); ++i) {
    const BandDensity &g = r.gyro_flight_spectrum[i], &a = r.accel_flight_spectrum[i];
    for (const NoiseBand &b : m.flight_spectrum) {
      // Bands of the model well above the datasheet floor, and the measurement's band inside them.
      if (g.low_hz < b.low_hz || g.high_hz > b.high_hz || b.gyro.minCoeff() < 5e-4 || g.samples == 0)
        continue;
      std::cout << "[ measured ] " << g.low_hz << "-" << g.high_hz << " Hz: gyro " << g.density.transpose()
                << " (model " << b.gyro.transpose() << "), accel " << a.density.transpose() << " (model "
                << b.accel.transpose() << ")\n";
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(g.density(k), b.gyro(k), 0.3 * b.gyro(k)) << "gyro axis " << k << " band " << g.low_hz;
        EXPECT_NEAR(a.density(k), b.accel(k), 0.3 * b.accel(k)) << "accel axis " << k << " band " << g.low_hz;
      }
      ++checked;
    }
  }
  EXPECT_GE(checked, 4);
  EXPECT_LT((r.gyro_bias - m.gyro_bias0).norm(), 2e-3);
  // The coloured noise limits how well 150 s resolve the gyro's scale and axes: to ~3e-3 (docs/simulate.md says so
  // of the real log's fit, whose deviations from identity are of that size).
  EXPECT_LT((r.gyro_S - m.gyro_scale_misalignment).cwiseAbs().maxCoeff(), 4e-3);
}

TEST(SimImuErrors, RealV101LogAgreesWithEurocsBiasesAndWithThePreset) {
  OVTEST_REQUIRE_SHARED_DATA();
  const std::string cut = ovtest::shared_data() + "/euroc_v1_01_moving";
  if (!std::filesystem::is_directory(cut))
    GTEST_SKIP() << cut << " not found";
  ov_core::LoadOptions lo;
  lo.check_images_exist = false;
  const ov_core::Dataset d = ov_core::load_dataset(cut, lo);
  const ImuMatchReport r = match_imu(d.imu, d.groundtruth);
  std::cout << imu_match_yaml(r);
  // EuRoC's ground truth carries its own gyro bias estimate: (-0.00225, 0.0215, 0.0770) rad/s at the start.
  EXPECT_LT((r.gyro_bias - d.groundtruth.front().bg).norm(), 1.5e-3);
  EXPECT_LT(std::abs(r.gt_shift_s), 0.002);
  EXPECT_LT(r.gt_rotation.norm() * 180 / M_PI, 0.1);
  // The preset's numbers are this measurement's (so they cannot drift apart silently).
  const ImuErrorModel m = euroc_v1_01_imu_errors();
  EXPECT_LT((r.gyro_S - m.gyro_scale_misalignment).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_LT((r.gyro_bias - m.gyro_bias0).norm(), 1e-4);
  for (size_t i = 0; i < r.gyro_flight_spectrum.size(); ++i) {
    const BandDensity &g = r.gyro_flight_spectrum[i], &a = r.accel_flight_spectrum[i];
    for (const NoiseBand &b : m.flight_spectrum)
      if (g.low_hz == b.low_hz && g.high_hz <= b.high_hz && (g.high_hz <= 2.0 || g.low_hz >= 20.0))
        for (int k = 0; k < 3; ++k) {
          EXPECT_NEAR(g.density(k), b.gyro(k), 0.06 * b.gyro(k)) << "band " << g.low_hz << " gyro " << k;
          EXPECT_NEAR(a.density(k), b.accel(k), 0.06 * b.accel(k)) << "band " << g.low_hz << " accel " << k;
        }
  }
}

TEST(SimImuErrors, DeclaredNoiseIsTheAllanFitOfWhatTheLogCarries) {
  // 1. allan_variance() against the overlapping Allan variance of a synthetic log's noise (datasheet white noise,
  //    bias walk and the euroc model's coloured noise; scale and turn-on biases left out: they are not noise).
  const LissajousTrajectory traj(300.0);
  ImuSynthOptions io = datasheet_imu(21);
  io.add_bias_walk = true;
  io.calib.gyro_random_walk = 1.9393e-5;
  io.calib.accel_random_walk = 3.0e-3;
  ImuSynthResult noisy = synthesize_imu(traj, io);
  ImuErrorModel m = euroc_v1_01_imu_errors();
  m.gyro_scale_misalignment.setIdentity();
  m.gyro_bias0.setZero();
  m.accel_bias0.setZero();
  add_imu_errors(traj, m, io.calib.gyro_noise_density, io.calib.accel_noise_density, 22, noisy.imu, noisy.truth);
  ImuSynthOptions clean_opt = io;
  clean_opt.add_noise = clean_opt.add_bias_walk = false;
  const ImuSynthResult clean = synthesize_imu(traj, clean_opt);
  ASSERT_EQ(clean.imu.size(), noisy.imu.size());
  const size_t n = noisy.imu.size();
  const auto empirical = [&](bool gyro, double tau) { // overlapping Allan variance, averaged over the axes
    const size_t k = static_cast<size_t>(std::lround(tau * 200.0));
    std::vector<Eigen::Vector3d> c(n + 1, Eigen::Vector3d::Zero()); // cumulative sums of the error
    for (size_t i = 0; i < n; ++i)
      c[i + 1] = c[i] + (gyro ? noisy.imu[i].wm - clean.imu[i].wm : noisy.imu[i].am - clean.imu[i].am);
    double s = 0.0;
    size_t terms = 0;
    for (size_t i = 0; i + 2 * k <= n; ++i, ++terms)
      s += ((c[i + 2 * k] - 2.0 * c[i + k] + c[i]) / static_cast<double>(k)).squaredNorm() / 3.0;
    return 0.5 * s / static_cast<double>(terms);
  };
  for (const double tau : {0.05, 0.5, 2.0}) {
    for (const bool gyro : {true, false}) {
      double model = 0.0;
      for (int axis = 0; axis < 3; ++axis)
        model += allan_variance(m, gyro, axis, gyro ? io.calib.gyro_noise_density : io.calib.accel_noise_density,
                                gyro ? io.calib.gyro_random_walk : io.calib.accel_random_walk, tau) /
                 3.0;
      const double meas = empirical(gyro, tau);
      std::cout << "[ measured ] " << (gyro ? "gyro" : "accel") << " Allan deviation at " << tau << " s: log "
                << std::sqrt(meas) << ", model " << std::sqrt(model) << "\n";
      EXPECT_NEAR(meas / model, 1.0, tau < 1.0 ? 0.15 : 0.35) << (gyro ? "gyro" : "accel") << " tau " << tau;
    }
  }
  // 2. The fit: without the coloured noise it gives the datasheet back. With it, two parameters cannot follow the
  //    log's curve (it dips near 2 s and rises again: the wander's flat spectrum below 0.2 Hz), so the check is the
  //    fit's own property - declared/log balanced around 1 over the averaging times a filter spans (a frame to a
  //    run: the geometric mean of the ratio within 15 % of 1) - and its worst ratios, as measured (0.40-2.39).
  const ov_core::ImuCalib none = fitted_imu_noise(ImuErrorModel{}, io.calib);
  EXPECT_NEAR(none.gyro_noise_density / io.calib.gyro_noise_density, 1.0, 0.03);
  EXPECT_NEAR(none.accel_random_walk / io.calib.accel_random_walk, 1.0, 0.03);
  const ov_core::ImuCalib fit = fitted_imu_noise(m, io.calib);
  std::cout << "[ measured ] declared: gyro " << fit.gyro_noise_density << " rad/s/sqrt(Hz), walk "
            << fit.gyro_random_walk << "; accel " << fit.accel_noise_density << ", walk " << fit.accel_random_walk
            << "\n";
  EXPECT_GT(fit.gyro_noise_density, 4 * io.calib.gyro_noise_density); // the datasheet understates it
  for (const bool gyro : {true, false}) {
    double log_sum = 0.0;
    int count = 0;
    for (double tau = 0.05; tau < 20.01; tau *= std::pow(400.0, 1.0 / 24), ++count) {
      double model = 0.0;
      for (int axis = 0; axis < 3; ++axis)
        model += allan_variance(m, gyro, axis, gyro ? io.calib.gyro_noise_density : io.calib.accel_noise_density,
                                gyro ? io.calib.gyro_random_walk : io.calib.accel_random_walk, tau) /
                 3.0;
      const double N = gyro ? fit.gyro_noise_density : fit.accel_noise_density;
      const double K = gyro ? fit.gyro_random_walk : fit.accel_random_walk;
      const double ratio = (N * N / tau + K * K * tau / 3.0) / model;
      log_sum += std::log(ratio);
      EXPECT_GT(ratio, 0.35) << (gyro ? "gyro" : "accel") << " tau " << tau;
      EXPECT_LT(ratio, 2.5) << (gyro ? "gyro" : "accel") << " tau " << tau;
    }
    EXPECT_NEAR(std::exp(log_sum / count), 1.0, 0.15) << (gyro ? "gyro" : "accel");
  }
}

TEST(SimImuErrors, DroppedPartsLeaveTheRestOfTheModel) {
  ImuErrorModel m = euroc_v1_01_imu_errors();
  const size_t bands = m.flight_spectrum.size();
  drop_imu_error_parts(m, "slow,scale");
  EXPECT_TRUE(m.gyro_scale_misalignment.isIdentity());
  EXPECT_GT(m.gyro_bias0.norm(), 0.0); // turn-on biases kept
  ASSERT_FALSE(m.flight_spectrum.empty());
  EXPECT_LT(m.flight_spectrum.size(), bands);
  for (const NoiseBand &b : m.flight_spectrum)
    EXPECT_GE(b.low_hz, 2.0);
  ImuErrorModel g = euroc_v1_01_imu_errors();
  drop_imu_error_parts(g, "vibration-gyro");
  for (const NoiseBand &b : g.flight_spectrum) {
    EXPECT_EQ(b.gyro.isZero(), b.low_hz >= 10.0);
    EXPECT_FALSE(b.accel.isZero());
  }
  drop_imu_error_parts(m, "turn-on,mid,vibration");
  EXPECT_TRUE(m.gyro_bias0.isZero() && m.accel_bias0.isZero());
  EXPECT_TRUE(m.flight_spectrum.empty());
  EXPECT_THROW(drop_imu_error_parts(m, "scale,wobble"), ov_core::UsageError);
}
