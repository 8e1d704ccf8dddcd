// `diagnose` on residual logs of SIMULATED data with planted effects (ovton simulate --features-only):
//  - true-pose logs: every feature track triangulated with the TRUE camera poses, so that only its point can absorb
//    an effect. Checks diagnose's point projection and the sizes of the camera-side effects against a known truth.
//  - the filter's own logs (VioManager with a residual log, as `ovton run --residual-log`): a time-offset drift, a
//    constant offset, a readout time, a focal error and clean data. The filter's state absorbs all but the first of
//    these from its residual; with the raw gyro diagnose tests them on the images' rates instead (docs/diagnose.md).
//  The rolling-shutter cases fly the built-in flight with agility 1: a readout shows in rates only through the angular
//  acceleration (ψ = α·t_r), and the plain flight's ≈ 0.15 rad/s² leaves t_r at ±5 ms (measured: 15.2 ± 4.8 ms for
//  25 through the filter, 14.0 ± 5.3 ms with the true poses).
#include "diagnose_test_util.h"
#include "estimator_test_util.h"
#include "ov_core/io/dataset.h"
#include "ov_core/math/so3.h"
#include "ov_eval/diagnose.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_msckf_ton/update/residual_log.h"
#include "ov_sim/simulator.h"
#include "test_util.h"

#include <chrono>
#include <cmath>
#include <functional>
#include <iostream>
#include <map>

using namespace ovton::core;
using namespace ovton::eval;
using ovtest::estimate;
using ovtest::expect_nothing_flagged;
using ovtest::expect_top;
using ovtest::top;

namespace {

/// A feature-level simulation along the built-in flight with planted effects.
struct Plant {
  double td0_s = 0.010, td_rate = 0.0; ///< time offset; drift: deterministic rate, no random walk
  double readout_s = 0.0;              ///< rolling shutter
  double focal_error = 0.0;            ///< relative
  double duration_s = 20.0;
  double agility = 0.0;    ///< the built-in flight's extra angular oscillations (ovton::sim::LissajousTrajectory)
  double gyro_scale = 0.0; ///< relative: the gyro reads (1 + s)·ω
  Eigen::Matrix3d gyro_M = Eigen::Matrix3d::Zero(), accel_M = Eigen::Matrix3d::Zero(); ///< (I + M)·ω, (I + M)·f
  Eigen::Vector3d ext_rot = Eigen::Vector3d::Zero();   ///< R_BC true = Exp(ext_rot)·R_BC [rad]
  Eigen::Vector3d ext_trans = Eigen::Vector3d::Zero(); ///< p_BC true = p_BC + ext_trans [m]
  double wander_s = 0.0, wander_period_s = 10.0;       ///< offset td0 + A·sin(2π·t/P)
  /// The IMU `ovton simulate` makes by default (realism euroc): the error model measured on the real V1_01 log, whose
  /// gyro vibrates (10-100 Hz bands). Off: the datasheet's white noise and bias walk only.
  bool euroc_imu = false;
  int seed = 7;
};

ovton::sim::SimOptions sim_options(const std::string &dir, const Plant &p) {
  ovton::sim::SimOptions o;
  o.out_dir = dir;
  o.duration_s = p.duration_s;
  o.seed = p.seed;
  o.features_only = true;
  o.td.kind = p.td_rate != 0.0    ? ovton::sim::TdModelKind::Drift
              : p.wander_s != 0.0 ? ovton::sim::TdModelKind::Wander
                                  : ovton::sim::TdModelKind::Constant;
  o.td.wander_amplitude_s = p.wander_s;
  o.td.wander_period_s = p.wander_period_s;
  o.gyro_M = p.gyro_M;
  o.accel_M = p.accel_M;
  o.extrinsic_rot = p.ext_rot;
  o.extrinsic_trans = p.ext_trans;
  o.td.td0_s = p.td0_s;
  o.td.bias_s_per_s = p.td_rate;
  o.td.noise_s_per_sqrt_s = 0.0;
  o.readout_s = p.readout_s;
  o.agility = p.agility;
  o.gyro_scale = p.gyro_scale;
  o.focal_error = p.focal_error;
  if (p.euroc_imu)
    o.imu_errors = ovton::sim::euroc_v1_01_imu_errors();
  return o;
}

/// What `ovton diagnose --dataset DIR` passes: the dataset's camera and raw IMU.
DiagnoseOptions diagnose_options(const Dataset &data) {
  DiagnoseOptions d;
  d.camera = data.cam;
  d.have_camera = true;
  d.imu = data.imu;
  return d;
}

/// Residual log with the TRUE camera poses at t_cam + td_model (td_model NaN: each image's true offset). Every track is
/// cut into windows of at most 20 frames as the filter's, its point triangulated (Gauss-Newton on the normalised
/// reprojection error) with the camera of sensor.yaml, and its residuals written as the filter writes them.
void write_true_pose_log(const ovton::sim::SimOptions &o, const Dataset &data, double td_model_s,
                         const std::string &file) {
  const auto traj = ovton::sim::make_trajectory(o);
  const CameraModel cam(data.cam);
  struct Obs {
    size_t frame;
    Eigen::Vector2d uv, xn;
  };
  std::map<size_t, std::vector<Obs>> tracks;
  const size_t nf = data.images.size();
  std::vector<Eigen::Matrix3d> R_WC(nf);
  std::vector<Eigen::Vector3d> p_WC(nf), w_B(nf);
  std::vector<double> td(nf);
  for (size_t k = 0; k < nf; ++k) {
    const int64_t t_cam = data.images[k].t_cam_ns;
    td[k] = std::isnan(td_model_s) ? data.td_truth_at(t_cam) : td_model_s;
    const auto s = traj->sample(t_cam + s_to_ns(td[k]));
    ovton::sim::camera_pose(s, data.cam.T_BC, R_WC[k], p_WC[k]);
    w_B[k] = s.w_B;
    for (const auto &f : *data.images[k].features)
      tracks[f.id].push_back({k, f.uv, cam.undistort(f.uv)});
  }
  ovton::msckf::ResidualLogWriter log(file);
  const double fu = data.cam.intrinsics(0), fv = data.cam.intrinsics(1);
  for (const auto &[id, all] : tracks) {
    for (size_t c0 = 0; c0 + 3 <= all.size(); c0 += 20) {
      const std::vector<Obs> tr(all.begin() + c0, all.begin() + std::min(all.size(), c0 + 20));
      // Linear start (the point closest to the bearings), then Gauss-Newton.
      Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
      Eigen::Vector3d b = Eigen::Vector3d::Zero();
      for (const auto &ob : tr) {
        const Eigen::Vector3d dir = (R_WC[ob.frame] * ob.xn.homogeneous()).normalized();
        const Eigen::Matrix3d Pm = Eigen::Matrix3d::Identity() - dir * dir.transpose();
        A += Pm, b += Pm * p_WC[ob.frame];
      }
      Eigen::Vector3d P = A.ldlt().solve(b);
      for (int it = 0; it < 8; ++it) {
        Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
        Eigen::Vector3d g = Eigen::Vector3d::Zero();
        for (const auto &ob : tr) {
          const Eigen::Vector3d pc = R_WC[ob.frame].transpose() * (P - p_WC[ob.frame]);
          Eigen::Matrix<double, 2, 3> J;
          J << 1 / pc.z(), 0, -pc.x() / (pc.z() * pc.z()), 0, 1 / pc.z(), -pc.y() / (pc.z() * pc.z());
          J = J * R_WC[ob.frame].transpose();
          const Eigen::Vector2d e = ob.xn - pc.head<2>() / pc.z();
          H += J.transpose() * J, g += J.transpose() * e;
        }
        P += H.ldlt().solve(g);
      }
      std::vector<ovton::msckf::ResidualRecord> recs;
      for (size_t j = 0; j < tr.size(); ++j) {
        const Obs &ob = tr[j];
        const Eigen::Vector3d pc = R_WC[ob.frame].transpose() * (P - p_WC[ob.frame]);
        ovton::msckf::ResidualRecord r;
        r.update_id = tr.back().frame; // the filter updates a track when it ends: tracks ending together share clones
        r.t_cam_ns = data.images[ob.frame].t_cam_ns;
        r.feature_id = id;
        r.obs_index = static_cast<int>(j);
        r.track_length = static_cast<int>(tr.size());
        r.res_u_px = fu * (ob.xn.x() - pc.x() / pc.z());
        r.res_v_px = fv * (ob.xn.y() - pc.y() / pc.z());
        r.u_px = ob.uv.x(), r.v_px = ob.uv.y();
        r.x_norm = ob.xn.x(), r.y_norm = ob.xn.y();
        r.radius_norm = ob.xn.norm();
        r.depth_m = pc.z();
        r.w_x = w_B[ob.frame].x(), r.w_y = w_B[ob.frame].y(), r.w_z = w_B[ob.frame].z();
        r.w_valid = 1;
        r.td_s = r.td_ref_s = td[ob.frame];
        r.accepted = 1;
        recs.push_back(r);
      }
      log.write(recs);
    }
  }
}

/// Edits the calibration log the filter wrote beside its residual log, before diagnose reads it.
using CalibEdit = std::function<void(std::vector<CalibrationLogRow> &)>;

/// The filter on the simulation (mode, t_d fixed or started at td_init_s, ground-truth initialisation), its
/// residual log diagnosed with its calibration log (edited by `edit`, when one is given). Prints the ranking and the
/// wall time.
DiagnoseReport filter_case(const Plant &p, const std::string &mode, double td_init_s, const CalibEdit &edit = {},
                           const ovton::msckf::CalibrationOptions &calibration = {}) {
  const auto t0 = std::chrono::steady_clock::now();
  ovtest::TempDir dir;
  const ovton::sim::SimOptions o = sim_options(dir / "sim", p);
  ovton::sim::write_simulation(o);
  const Dataset data = load_dataset(o.out_dir);
  ovton::msckf::VioOptions opt;
  opt.td.mode = ovton::msckf::parse_td_mode(mode);
  opt.td.init_s = td_init_s;
  opt.init.mode = ovton::msckf::InitMode::GroundTruth;
  opt.update.msckf.sigma_px = o.features.pixel_noise;
  opt.calibration = calibration;
  opt.td.search.enabled = false; // the filter alone, from td_init_s
  const std::string log_file = dir / "res.csv";
  ovtest::run_estimator(data, opt, {std::make_shared<ovton::msckf::ResidualLogObserver>(log_file)});
  DiagnoseOptions dopt = diagnose_options(data); // with the calibration log, as `ovton diagnose` reads it
  dopt.calibration = load_calibration_log(calibration_log_path(log_file));
  if (edit)
    edit(dopt.calibration);
  const DiagnoseReport rep = diagnose(load_residual_log(log_file), dopt);
  std::cout << format_ranking(rep) << "[ measured ] mode " << mode << ", "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s\n";
  return rep;
}

/// A simulation and its true-pose log (td_model_s as in write_true_pose_log), diagnosed with --dataset.
class TruePoseLog {
public:
  TruePoseLog(const Plant &p, double td_model_s) : o_(sim_options(dir_ / "sim", p)), td_model_s_(td_model_s) {
    ovton::sim::write_simulation(o_);
    data_ = load_dataset(o_.out_dir);
    write_true_pose_log(o_, data_, td_model_s, dir_ / "res.csv");
  }

  /// calib_readout_s >= 0: with a calibration log of one row per image, the dataset's calibration and this readout
  /// time estimated (a filter that has absorbed the readout).
  DiagnoseReport diagnose(double calib_readout_s = -1.0) const {
    DiagnoseOptions dopt = diagnose_options(data_);
    for (size_t k = 0; calib_readout_s >= 0.0 && k < data_.images.size(); ++k) {
      CalibrationLogRow r;
      r.update_id = k;
      r.t_cam_ns = data_.images[k].t_cam_ns;
      r.estimated = CalibrationLogRow::kReadout;
      r.td_s = td_model_s_;
      for (int i = 0; i < 9; ++i)
        r.R_BC[i] = data_.cam.T_BC(i / 3, i % 3);
      for (int i = 0; i < 3; ++i)
        r.p_BC[i] = data_.cam.T_BC(i, 3);
      for (int i = 0; i < 4; ++i)
        r.intrinsics[i] = data_.cam.intrinsics(i), r.intrinsics[4 + i] = data_.cam.dist_coeffs(i);
      r.readout_s = calib_readout_s;
      dopt.calibration.push_back(r);
    }
    const DiagnoseReport rep = ovton::eval::diagnose(load_residual_log(dir_ / "res.csv"), dopt);
    std::cout << format_ranking(rep);
    return rep;
  }

private:
  ovtest::TempDir dir_;
  ovton::sim::SimOptions o_;
  double td_model_s_;
  Dataset data_;
};

DiagnoseReport true_pose_case(const Plant &p, double td_model_s) {
  return TruePoseLog(p, td_model_s).diagnose();
}

} // namespace

// Camera-side effects with true poses: only the points absorb. The readout case models the right mean offset (poses
// at the mid-row instant, as a filter estimating t_d would have them), so the row-dependent part is what is left.
TEST(DiagnoseTruePoses, RollingShutterRankedFirstAndSized) {
  Plant p;
  p.readout_s = 0.025;
  p.agility = 1.0;
  expect_top(true_pose_case(p, p.td0_s + 0.5 * p.readout_s), "rolling_shutter", "readout time t_r", 25.0, 5.0);
}

// The same with the IMU `ovton simulate` makes by default, whose gyro vibrates. ψ is compared with the gyro through the
// images' slope (rate_design.cpp, GyroSlope); the ±50-ms difference it replaced carried the vibration, an error in
// the regressor that scaled the estimate down: 20 ms read 16.4 ms here, and with a calibration log holding the true
// readout (a filter that has estimated it) −3.6 ms were left, flagged at 6.6σ; now 19.8 and −0.2 ms. (The filter's
// `sr` logs of the 30-s flights, seeds 1-4: 16.5-17.0 ms, now 18.6-19.2; docs/diagnose.md.)
TEST(DiagnoseTruePoses, RollingShutterSizedWithAVibratingGyro) {
  Plant p;
  p.readout_s = 0.020;
  p.agility = 1.0;
  p.euroc_imu = true;
  const double td_mid = p.td0_s + 0.5 * p.readout_s;
  const TruePoseLog log(p, td_mid);
  expect_top(log.diagnose(), "rolling_shutter", "readout time t_r", 20.0, 1.5);
  const DiagnoseReport after = log.diagnose(p.readout_s);
  for (const auto &c : after.candidates)
    if (c.key == "rolling_shutter") {
      EXPECT_FALSE(c.explained) << format_ranking(after);
      EXPECT_NEAR(estimate(c, "readout time t_r"), 0.0, 1.5) << format_ranking(after);
    }
}

// The focal column is the secant of the rates' response from the data back to no error (the response is not linear):
// 1.03 % here; with the +1 % step alone it read 0.90 % (docs/diagnose.md, "What the focal reading is made of").
TEST(DiagnoseTruePoses, FocalErrorRankedFirstAndSized) {
  Plant p;
  p.focal_error = 0.01;
  expect_top(true_pose_case(p, p.td0_s), "focal", "relative focal error ε", 1.0, 0.08);
}

// The rate model's own bias on agile motion: with true poses, noise-free tracks and no IMU noise, ω̄_gyro turned the
// features by the gyro alone while the images also translate, and the slope's distortion of the combined motion read
// as a 0.20 % gyro scale on this flight (0.16 % on seed 1). ω̄ now moves them by the fitted velocity too: 0.00 %.
TEST(DiagnoseTruePoses, AgileFlightReadsNoGyroScaleNoiseFree) {
  Plant p;
  p.agility = 1.0;
  p.seed = 3;
  ovtest::TempDir dir;
  ovton::sim::SimOptions o = sim_options(dir / "sim", p);
  o.features.pixel_noise = 0.0;
  o.imu_noise = false;
  ovton::sim::write_simulation(o);
  const Dataset data = load_dataset(o.out_dir);
  write_true_pose_log(o, data, p.td0_s, dir / "res.csv");
  const DiagnoseReport rep = ovton::eval::diagnose(load_residual_log(dir / "res.csv"), diagnose_options(data));
  std::cout << format_ranking(rep);
  for (const auto &c : rep.candidates)
    if (c.key == "gyro_scale")
      EXPECT_NEAR(estimate(c, "gyro scale error s"), 0.0, 0.05) << format_ranking(rep);
}

TEST(DiagnoseTruePoses, CleanDataFlagsNothing) {
  expect_nothing_flagged(true_pose_case(Plant{}, std::nan("")));
}

// Through the filter. Mode `off` holds t_d at its configured value, here the true offset at the start, so the model
// lacks exactly the drift (1 ms/s: 10 → 40 ms over 30 s). The filter's poses absorb the offset error (the residual
// shows < 0.1 ms of it, docs/diagnose.md); the time candidates read it from the images' angular rate against the
// gyro's. That rate fit needs depths, and the filter's are triangulated with poses from the wrong instant: without
// diagnose's per-track inverse-depth correction the drift read as 0.71 ms/s and the 30 ms offset below as 23.0 ms
// (seeds 1-4: 1.00, 0.88, 0.65, 0.95 ms/s; 15.4, 23.1, 20.3, 21.5 ms). With it: 0.96 ± 0.09 ms/s and 29.4 ± 1.6 ms
// (seeds 1-4: 1.12, 1.10, 0.85, 1.19 ms/s; 20.3, 29.4, 27.4, 28.3 ms — the same as with the true geometry's depths
// in place of the filter's: 1.15, 1.07, 0.90, 1.21 ms/s; 22.9, 29.0, 26.1, 28.3 ms). (0.5 ms/s over 30 s: see
// docs/diagnose.md.) Since the depth correction uses the fits with ψ (rolling shutter), seed 7 reads 0.875 ± 0.075
// ms/s and 29.3 ± 1.7 ms.
TEST(DiagnoseFilterLog, TimeOffsetDriftRankedFirstAndSized) {
  Plant p;
  p.td_rate = 0.001;
  p.duration_s = 30.0;
  const auto r = filter_case(p, "off", p.td0_s);
  expect_top(r, "td_drift", "drift rate", 1.0, 0.2);
  ASSERT_GE(r.td_bins.size(), 6u);
  EXPECT_GT(r.td_bins.back().td_ms, r.td_bins.front().td_ms + 15.0); // the per-bin trend shows the drift
}

TEST(DiagnoseFilterLog, CleanDataFlagsNothing) {
  expect_nothing_flagged(filter_case(Plant{}, "off", Plant{}.td0_s));
}

// A constant offset the filter holds wrong (t_d fixed at 0, truth 30 ms): named and sized from the rates.
TEST(DiagnoseFilterLog, ConstantOffsetRankedFirstAndSized) {
  Plant p;
  p.td0_s = 0.030;
  p.duration_s = 10.0;
  expect_top(filter_case(p, "off", 0.0), "td_const", "offset error δt", 30.0, 6.0);
}

// The same offset with the IMU `ovton simulate` makes by default (its gyro vibrates) on the plain flight, whose angular
// acceleration is weak. The time rows used to compare the images with the raw gyro at the image's instant and α with
// a ±50 ms difference of it, both carrying the vibration, on rows of their own: the offset read 2-3 ms and the
// rotation rows, with no time column, named a 1.35° camera-IMU rotation (6.4σ) instead. Now one set of ω rows against
// the gyro through the images' estimator carries the time and the rotation columns jointly: 29.0 ± 2.3 ms.
TEST(DiagnoseFilterLog, ConstantOffsetWithAVibratingGyroIsNotARotation) {
  Plant p;
  p.td0_s = 0.030;
  p.euroc_imu = true;
  const auto r = filter_case(p, "off", 0.0);
  expect_top(r, "td_const", "offset error δt", 30.0, 6.0);
  for (const auto &c : r.candidates)
    EXPECT_FALSE(c.key == "extrinsic_rotation" && c.explained) << format_ranking(r);
}

// A readout time and a focal error the filter's state absorbs from its residual (there they read 5.90 ± 0.43 ms for
// 25 ms and 0.086 ± 0.008 % for 1 %): named and sized from the rates. Seeds 1-4 (docs/diagnose.md): readout 23.7,
// 23.8, 22.8, 23.6 ms; focal 0.96, 0.88, 1.05, 1.04 %.
TEST(DiagnoseFilterLog, RollingShutterRankedFirstAndSized) {
  Plant p;
  p.readout_s = 0.025;
  p.agility = 1.0;
  expect_top(filter_case(p, "off", p.td0_s + 0.5 * p.readout_s), "rolling_shutter", "readout time t_r", 25.0, 5.0);
}

// Named by the rates' focal column, sized from two views and the gyro (focal_two_view.h): 1.09 ± 0.07 % here, the
// rates' column 0.92 %; on the sizing flights the column read 0.58-1.01 %, the two views 0.96-1.13 % (seeds 1-7).
TEST(DiagnoseFilterLog, FocalErrorRankedFirstAndSized) {
  Plant p;
  p.focal_error = 0.01;
  const auto r = filter_case(p, "off", p.td0_s);
  expect_top(r, "focal", "relative focal error ε", 1.0, 0.2);
  if (!r.candidates.empty() && top(r).key == "focal") {
    EXPECT_NE(top(r).note.find("sized from two views"), std::string::npos) << top(r).note;
    EXPECT_GT(estimate(top(r), "relative focal error ε (rates)"), 0.0) << format_ranking(r);
  }
}

// A gyro scale error: the filter's poses follow the images, its residual does not show it (on the residual it was not
// among the top three, seeds 1-2); the images' rotation against the gyro does, where the rate varies within the gyro
// bias's 5-s bins. Agile flight, seeds 1-4 and this one (7): 1.19, 1.19, 1.14, 1.21, 1.10 % (clean agile flights read
// +0.18 to +0.26 %). The plain flight is too steady: 0.85, 1.10, 0.71 ± 0.14 % over 20 s; 1.10 ± 0.10 % over 40 s (seed
// 7).
TEST(DiagnoseFilterLog, GyroScaleRankedFirstAndSized) {
  Plant p;
  p.gyro_scale = 0.01;
  p.agility = 1.0;
  expect_top(filter_case(p, "off", p.td0_s), "gyro_scale", "gyro scale error s", 1.0, 0.2);
}

// Issue 16's undeclared effects, through the filter (t_d held at the truth, so only the planted effect is missing).
// A camera-IMU rotation error below 1°: on rates the images' rotation is the gyro's turned by φ.
TEST(DiagnoseFilterLog, ExtrinsicRotationRankedFirstAndSized) {
  Plant p;
  p.ext_rot = Eigen::Vector3d(0.3, -0.4, 0.5) * M_PI / 180.0; // |φ| = 0.707°
  p.agility = 1.0;
  expect_top(filter_case(p, "off", p.td0_s), "extrinsic_rotation", "rotation error |φ|", 0.707, 0.14);
}

// A 3 % scale error on the gyro's z axis alone: the per-axis candidate, not the isotropic one, names it.
TEST(DiagnoseFilterLog, GyroScaleOneAxisRankedFirstAndSized) {
  Plant p;
  p.gyro_M(2, 2) = 0.03;
  p.agility = 1.0;
  const auto r = filter_case(p, "off", p.td0_s);
  expect_top(r, "gyro_scale_axes", "gyro scale error s_z", 3.0, 0.6);
  if (!r.candidates.empty() && top(r).key == "gyro_scale_axes") {
    EXPECT_NEAR(estimate(top(r), "gyro scale error s_x"), 0.0, 0.6) << format_ranking(r);
    EXPECT_NEAR(estimate(top(r), "gyro scale error s_y"), 0.0, 0.6) << format_ranking(r);
  }
}

// A gyro whose axes are not orthogonal: M's symmetric off-diagonal (xy, xz, yz) = (15, -12, 9) mrad, |m| 21.2 mrad. On
// rates its mismatch −M·ω̄ cannot be a camera-body rotation (antisymmetric), so it has its own candidate. Its standard
// error here is ~0.85 mrad whatever the size: at a third of this size (7.07 mrad) the GCC build read 7.66 and the clang
// (sanitizer) build 5.55, at (10, -8, 6) 14.62 and 12.75 — the filter amplifies last-bit differences, by ~2 mrad
// whatever the size — so the planted size keeps 20 % beyond that spread.
TEST(DiagnoseFilterLog, GyroMisalignmentRankedFirstAndSized) {
  Plant p;
  p.gyro_M(0, 1) = p.gyro_M(1, 0) = 0.015;
  p.gyro_M(0, 2) = p.gyro_M(2, 0) = -0.012;
  p.gyro_M(1, 2) = p.gyro_M(2, 1) = 0.009;
  p.agility = 1.0;
  const auto r = filter_case(p, "off", p.td0_s);
  expect_top(r, "gyro_misalignment", "gyro misalignment |m|", 21.21, 4.24);
  if (!r.candidates.empty() && top(r).key == "gyro_misalignment") { // a component: SE 1.1-1.4 mrad, builds ~2 apart
    EXPECT_NEAR(estimate(top(r), "gyro misalignment m_xy"), 15.0, 5.0) << format_ranking(r);
  }
}

// An offset wandering ±8 ms over 10 s around the filter's (true mean) t_d, without a trend: neither a constant nor a
// drift, the piecewise offset names it. Over 2.5-s bins a sine's bin means are ±(2/π)·A: spread 5.09 ms. (±4 ms is
// sized but not flagged: 2.61 ± 0.31 ms for 2.55 at 10σ, 0.95 % share under the 2 % bar, sr on 30 s; clean agile
// flights read a spread of 1.3-2.0 ms, 0.2-0.4 % share: the rates' per-bin offsets have a floor.)
TEST(DiagnoseFilterLog, WanderingOffsetRankedFirstAndSized) {
  Plant p;
  p.wander_s = 0.008;
  p.agility = 1.0;
  const auto r = filter_case(p, "off", p.td0_s);
  expect_top(r, "td_piecewise", "offset error spread (RMS over bins)", 5.09, 1.02);
}

// A 3 % accelerometer scale: no image shows it and the trajectory's size takes its isotropic part; gravity, turned in
// the body frame by the attitude, does not scale (the design against gravity, accel_design.h).
TEST(DiagnoseFilterLog, AccelerometerScaleRankedFirstAndSized) {
  Plant p;
  p.accel_M = Eigen::Matrix3d::Identity() * 0.03;
  p.agility = 1.0;
  // 3.45 ± 0.51 % at 5.5σ here (seeds 1-4: 3.01, 2.97 at 4.8σ, 3.20, 3.34). Over 30 s the same flights read 2.3-2.5 %
  // at 5.4-6.0σ: in the last 10 s the filter's velocity has taken most of it (docs/diagnose.md); the tolerance is the
  // design's spread, and the design on the filter's bias read 1.2-1.7 % for 3.
  expect_top(filter_case(p, "off", p.td0_s), "accel_scale", "accel scale error s", 3.0, 1.0);
}

TEST(DiagnoseFilterLog, CleanAgileDataFlagsNothing) {
  Plant p;
  p.agility = 1.0;
  expect_nothing_flagged(filter_case(p, "off", p.td0_s));
}

// Issue 16, "after": the filter's calibration (the calibration log beside the residual log) holds the planted effect,
// so diagnose, comparing the images with the IMU through it, must not name it again. The logs are the runs above
// with the effect not modelled; their calibration logs are set to the truth (a filter that has absorbed the effect).
// With the nominal calibration log, unedited, the effect is still named (the same as without one).
TEST(DiagnoseFilterLog, ExtrinsicRotationInTheCalibrationLogIsNotNamed) {
  Plant p;
  p.ext_rot = Eigen::Vector3d(0.3, -0.4, 0.5) * M_PI / 180.0;
  p.agility = 1.0;
  expect_top(filter_case(p, "off", p.td0_s, [](std::vector<CalibrationLogRow> &) {}), "extrinsic_rotation",
             "rotation error |φ|", 0.707, 0.14);
  expect_nothing_flagged(filter_case(p, "off", p.td0_s, [&](std::vector<CalibrationLogRow> &rows) {
    for (auto &r : rows) {
      Eigen::Matrix3d R;
      for (int i = 0; i < 9; ++i)
        R(i / 3, i % 3) = r.R_BC[i];
      R = ovton::core::so3_exp(p.ext_rot) * R;
      for (int i = 0; i < 9; ++i)
        r.R_BC[i] = R(i / 3, i % 3);
    }
  }));
}

// The gyro case's real "after": the filter estimates the IMU's intrinsics (D_w, D_a) and holds the planted scale in
// its calibration log. (Editing the unmodelled run's calibration log instead, as above, left that run's accelerometer
// bias in place, which the gyro error had moved: the candidate on that bias read 1-2.8 % at 4.6-11.7σ on seeds 1-4
// and 7, and the CI machine's libm tipped seed 7 over the bar. The accelerometer is now tested against gravity through
// the filter's D_a, accel_design.h.) Seed 7: largest gyro_scale_axes 2.6σ, 1.4 %; seeds 1-4 flag nothing but
// td_piecewise on seed 3 (6.0σ, 2.1 %: the clean-flight false flags of docs/diagnose.md).
TEST(DiagnoseFilterLog, GyroScaleEstimatedByTheFilterIsNotNamed) {
  Plant p;
  p.gyro_M(2, 2) = 0.03;
  p.agility = 1.0;
  ovton::msckf::CalibrationOptions calibration;
  calibration.imu_intrinsics = true;
  expect_nothing_flagged(filter_case(p, "off", p.td0_s, {}, calibration));
}
