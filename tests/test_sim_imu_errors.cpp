// The IMU error model (ov_sim/imu_errors.h) and its measurement (ov_sim/imu_match.h): the measurement finds a
// planted ground-truth time shift and frame rotation and keeps them apart from the IMU's own errors; a synthetic log
// with the euroc model, measured the same way, shows the spectrum the model asks for; on the real V1_01 log the
// measurement agrees with EuRoC's own bias estimate and still gives the numbers the euroc preset carries. A fine
// reference is moved onto a real IMU's clock, axes, gravity and origin (ov_sim/gt_alignment.h).
#include "ov_core/io/dataset.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/math/so3.h"
#include "ov_sim/gt_alignment.h"
#include "ov_sim/imu_errors.h"
#include "ov_sim/imu_match.h"
#include "ov_sim/imu_synth.h"
#include "ov_sim/simulator.h"
#include "ov_sim/trajectory.h"
#include "test_util.h"

#include <Eigen/Geometry>

using namespace ovton::sim;

namespace {

/// Ground truth of the built-in flight at 200 Hz (pose, velocity), as a reader would return it.
std::vector<ovton::core::StateSample> builtin_truth(const Trajectory &traj) {
  std::vector<ovton::core::StateSample> gt;
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
  std::vector<ovton::core::StateSample> gt = builtin_truth(traj);
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

TEST(SimGtAlignment, MovesAPlantedReferenceBackOntoTheImu) {
  // The IMU-frame truth and its noise-free IMU; a reference made from it stamped 3 ms late, its body axes rotated by
  // 0.6 deg, its world tilted by (0.1, -0.15) deg and its origin 45 mm from the IMU's (a marker's pose file).
  const LissajousTrajectory traj(60.0, LissajousTrajectory::kDefaultBeginNs, 1.0);
  const ImuSynthResult imu = synthesize_imu(traj, noise_free_imu());
  const std::vector<ovton::core::StateSample> truth = builtin_truth(traj);
  const Eigen::Matrix3d R_IB = ovton::core::so3_exp(Eigen::Vector3d(0.004, -0.006, 0.007)); // w_I = R_IB w_B
  const Eigen::Vector2d tilt(0.1 * M_PI / 180, -0.15 * M_PI / 180);
  const Eigen::Matrix3d R_WW1 = ovton::core::so3_exp(Eigen::Vector3d(tilt.x(), tilt.y(), 0.0)); // IMU world -> ref's
  const Eigen::Vector3d lever(0.002, -0.042, 0.006);
  std::vector<ovton::core::StateSample> ref, truth_20hz;
  for (size_t i = 0; i < truth.size(); ++i) {
    const ovton::core::StateSample &s = truth[i];
    const Eigen::Matrix3d R_W1I = s.q_WB.toRotationMatrix();
    ovton::core::StateSample r;
    r.t_ns = s.t_ns + 3000000;
    r.p = R_WW1 * (s.p - R_W1I * lever);
    r.q_WB = Eigen::Quaterniond(R_WW1 * R_W1I * R_IB);
    ref.push_back(r);
    if (i % 10 == 0)
      truth_20hz.push_back(s);
  }
  const GtAlignment a = align_gt_to_imu(imu.imu, ref, truth_20hz, 0.1);
  std::cout << "[ measured ] " << describe_gt_alignment(a) << "\n";
  EXPECT_NEAR(a.shift_s, 0.003, 0.0005);
  EXPECT_LT((ovton::core::so3_exp(a.rotation) * R_IB.transpose() - Eigen::Matrix3d::Identity()).norm(), 2e-4);
  EXPECT_LT((a.tilt - tilt).norm(), 2e-4);
  ASSERT_TRUE(a.lever_fitted);
  EXPECT_LT((a.lever_I - lever).norm(), 0.002);
  // Moved back, the reference is the truth (compared where the 3-ms shift leaves both defined).
  const std::vector<ovton::core::StateSample> back = apply_gt_alignment(ref, a);
  double worst_p = 0.0, worst_deg = 0.0;
  for (size_t i = 1; i + 1 < truth.size(); i += 37) {
    const ovton::core::StateSample &s = truth[i], &b = back[i];
    ASSERT_LT(std::abs(b.t_ns - s.t_ns), 600000);
    worst_p = std::max(worst_p, (b.p - s.p).norm());
    worst_deg = std::max(worst_deg, Eigen::AngleAxisd(b.q_WB.inverse() * s.q_WB).angle() * 180 / M_PI);
  }
  std::cout << "[ measured ] moved back: worst position " << worst_p * 1e3 << " mm, orientation " << worst_deg
            << " deg\n";
  EXPECT_LT(worst_p, 0.003);
  EXPECT_LT(worst_deg, 0.02);
}

TEST(SimGtAlignment, BlendKeepsTheEstimatesSlowMotionAndThePoseFilesFastMotion) {
  // Truth: the agile built-in flight with a fast wobble. The "estimate" is it at 20 Hz (its spline misses the fast
  // motion); the "pose file" is it at 200 Hz with a 0.6-deg wander at 0.15 Hz, a constant 3-deg body rotation and a
  // 30-mm offset (what a pose file does against the estimate). Blended at 1.5 Hz, each one's error goes.
  const LissajousTrajectory traj(30.0, LissajousTrajectory::kDefaultBeginNs, 2.0);
  std::vector<ovton::core::StateSample> truth = builtin_truth(traj);
  for (auto &s : truth) { // the airframe's fast motion: 0.3 deg and 1 mm at 6 Hz
    const double ph = 2 * M_PI * 6.0 * ovton::core::ns_to_s(s.t_ns - truth.front().t_ns);
    s.q_WB =
        Eigen::Quaterniond(s.q_WB.toRotationMatrix() *
                           ovton::core::so3_exp(0.3 * M_PI / 180 * Eigen::Vector3d(std::sin(ph), 0.0, std::cos(ph))));
    s.p += 0.001 * Eigen::Vector3d(0.0, std::sin(ph), 0.0);
  }
  std::vector<ovton::core::StateSample> estimate, pose_file;
  const Eigen::Matrix3d B = ovton::core::so3_exp(Eigen::Vector3d(0.03, -0.04, 0.02));
  for (size_t i = 0; i < truth.size(); ++i) {
    if (i % 10 == 0)
      estimate.push_back(truth[i]);
    ovton::core::StateSample f = truth[i];
    const double tau = ovton::core::ns_to_s(f.t_ns - truth.front().t_ns);
    const Eigen::Vector3d wander = 0.6 * M_PI / 180 * std::sin(2 * M_PI * 0.15 * tau) * Eigen::Vector3d(0.6, 0.0, 0.8);
    f.q_WB = Eigen::Quaterniond(f.q_WB.toRotationMatrix() * B * ovton::core::so3_exp(wander));
    f.p += Eigen::Vector3d(0.03, 0.0, 0.0);
    pose_file.push_back(f);
  }
  const std::vector<ovton::core::StateSample> blended = blend_gt(estimate, pose_file, 1.5, 0.1);
  const SplineTrajectory slow(estimate, estimate.front().t_ns, estimate.back().t_ns, 0.1);
  double e_blend = 0.0, e_slow = 0.0, e_file = 0.0, ep_blend = 0.0;
  int n = 0;
  for (size_t i = 0; i < blended.size(); ++i) {
    const ovton::core::StateSample &b = blended[i];
    const auto it = std::lower_bound(truth.begin(), truth.end(), b.t_ns,
                                     [](const ovton::core::StateSample &s, int64_t t) { return s.t_ns < t; });
    if (it == truth.end() || it->t_ns != b.t_ns || b.t_ns - truth.front().t_ns < ovton::core::s_to_ns(1.0) ||
        truth.back().t_ns - b.t_ns < ovton::core::s_to_ns(1.0))
      continue; // the ends: the low pass's kernel is cut there
    const Eigen::Matrix3d R = it->q_WB.toRotationMatrix();
    const auto deg = [&](const Eigen::Matrix3d &E) {
      return std::pow(ovton::core::so3_log(R.transpose() * E).norm() * 180 / M_PI, 2);
    };
    e_blend += deg(b.q_WB.toRotationMatrix());
    e_slow += deg(slow.sample(b.t_ns).q_WB.toRotationMatrix());
    e_file += deg(pose_file[it - truth.begin()].q_WB.toRotationMatrix() * B.transpose());
    ep_blend += (b.p - it->p).squaredNorm();
    ++n;
  }
  ASSERT_GT(n, 4000);
  e_blend = std::sqrt(e_blend / n), e_slow = std::sqrt(e_slow / n), e_file = std::sqrt(e_file / n);
  ep_blend = std::sqrt(ep_blend / n);
  std::cout << "[ measured ] orientation RMS error: blended " << e_blend << " deg, estimate's spline alone " << e_slow
            << ", pose file alone (its constant rotation removed) " << e_file << "; blended position " << ep_blend * 1e3
            << " mm\n";
  EXPECT_LT(e_blend, 0.3 * e_slow);
  EXPECT_LT(e_blend, 0.3 * e_file);
  EXPECT_LT(ep_blend, 0.002);
}

TEST(SimGtAlignment, EurocsPoseFileMovedOntoTheRealV101ImuAgreesWithIt) {
  // EuRoC's 200 Hz V1_01 pose file against the real log: its axes are 0.58 deg off the IMU's and its origin ~4 cm
  // from the IMU's (against state_groundtruth_estimate0, the IMU-frame estimate). Aligned, the log sees no rotation,
  // tilt or shift left, and the positions agree with the IMU-frame ground truth to a few millimetres.
  OVTEST_REQUIRE_SHARED_DATA();
  const std::string cut = ovtest::shared_data() + "/euroc_v1_01_moving";
  const std::string txt = ovtest::shared_data() + "/euroc_groundtruth/V1_01_easy.txt";
  if (!std::filesystem::is_directory(cut) || !std::filesystem::exists(txt))
    GTEST_SKIP() << cut << " or " << txt << " not found";
  ovton::core::LoadOptions lo;
  lo.check_images_exist = false;
  const ovton::core::Dataset d = ovton::core::load_dataset(cut, lo);
  const std::vector<ovton::core::StateSample> ref = ovton::core::read_trajectory(txt);
  const GtAlignment a = align_gt_to_imu(d.imu, ref, d.groundtruth, 0.05);
  std::cout << "[ measured ] " << describe_gt_alignment(a) << "\n";
  ASSERT_TRUE(a.lever_fitted);
  EXPECT_LT(a.lever_fit_rms_m, 0.005);
  EXPECT_GT(a.rotation.norm() * 180 / M_PI, 0.3); // what the alignment is for: the pose file is not in IMU axes
  ImuMatchOptions mo;
  mo.knot_dt_s = 0.05;
  const ImuMatchReport r = match_imu(d.imu, apply_gt_alignment(ref, a), mo);
  std::cout << "[ measured ] aligned: shift " << r.gt_shift_s * 1e3 << " ms, rotation "
            << r.gt_rotation.norm() * 180 / M_PI << " deg, tilt " << r.gt_tilt.norm() * 180 / M_PI << " deg\n";
  EXPECT_LT(std::abs(r.gt_shift_s), 0.0005);
  EXPECT_LT(r.gt_rotation.norm() * 180 / M_PI, 0.02);
  // Through the simulator (--gt TXT --align-gt CUT): --start-s still counts from the pose file's first pose, and the
  // blended trajectory is the 20 Hz estimate's to within the fast motion it misses (< 5 mm, 0.5 deg; not the pose
  // file's 4 cm lever arm or its 5 deg world yaw).
  SimOptions o;
  o.gt_file = txt;
  o.align_gt_to = cut;
  o.knot_dt_s = 0.05;
  o.start_s = 11.0;
  o.duration_s = 3.0;
  const auto traj = make_trajectory(o);
  EXPECT_NEAR(ovton::core::ns_to_s(traj->t_begin_ns() - ref.front().t_ns), 11.0 - a.shift_s, 1e-6);
  const SplineTrajectory est(d.groundtruth, traj->t_begin_ns(), traj->t_end_ns(), 0.1);
  double worst_p = 0.0, worst_deg = 0.0;
  for (int64_t t = traj->t_begin_ns() + 500000000; t < traj->t_end_ns() - 500000000; t += 50000000) {
    const TrajectorySample x = traj->sample(t), y = est.sample(t);
    worst_p = std::max(worst_p, (x.p_W - y.p_W).norm());
    worst_deg = std::max(worst_deg, Eigen::AngleAxisd(x.q_WB.inverse() * y.q_WB).angle() * 180 / M_PI);
  }
  std::cout << "[ measured ] blended against the estimate's spline: worst " << worst_p * 1e3 << " mm, " << worst_deg
            << " deg\n";
  EXPECT_LT(worst_p, 0.005);
  EXPECT_LT(worst_deg, 0.5);
  EXPECT_LT(r.gt_tilt.norm() * 180 / M_PI, 0.03); // from 0.1 deg
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
  ovton::core::LoadOptions lo;
  lo.check_images_exist = false;
  const ovton::core::Dataset d = ovton::core::load_dataset(cut, lo);
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
  const ovton::core::ImuCalib none = fitted_imu_noise(ImuErrorModel{}, io.calib);
  EXPECT_NEAR(none.gyro_noise_density / io.calib.gyro_noise_density, 1.0, 0.03);
  EXPECT_NEAR(none.accel_random_walk / io.calib.accel_random_walk, 1.0, 0.03);
  const ovton::core::ImuCalib fit = fitted_imu_noise(m, io.calib);
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
  EXPECT_THROW(drop_imu_error_parts(m, "scale,wobble"), ovton::core::UsageError);
}
