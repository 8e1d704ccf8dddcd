// `ovton diagnose` (ov_eval/diagnose.h): planted effects in synthetic residual logs are found and sized, a clean
// log flags nothing, bad logs fail with file:line. Logs of simulated data and of the filter: test_diagnose_sim.cpp.
#include "diagnose_test_util.h"
#include "ov_core/math/so3.h"
#include "ov_core/types/errors.h"
#include "ov_eval/diagnose.h"
#include "ov_eval/diagnose/candidates.h"
#include "ov_eval/diagnose/filter_calibration.h"
#include "ov_eval/diagnose/regression.h"
#include "ov_eval/diagnose/selection.h"
#include "ov_msckf_ton/update/residual_log.h"
#include "test_util.h"

#include <cmath>
#include <filesystem>
#include <iostream>
#include <random>

using namespace ovton::core;
using namespace ovton::eval;

namespace {

constexpr double kFu = 458.0, kFv = 457.0, kCu = 367.0, kCv = 248.0, kHeight = 480.0;

struct Planted {
  double td0_s = 0, td_rate = 0; ///< δt(t) = td0 + td_rate·t
  double readout_s = 0;          ///< rolling shutter
  double focal_eps = 0;          ///< relative focal error
};

/// A residual log as the filter would write it for a planted effect: tracks of 4–10 frames at 20 Hz of points 1–5 m
/// away seen by a rotating and translating camera (rates, velocities and accelerations of a hand-held flight, image
/// velocities of a few hundred px/s, positions over the whole image), pixel noise that sits both in the measured pixel
/// and in the residual, and the part a shift of the track's point could explain removed from the residual (what
/// triangulating the point from the same observations does to first order).
std::vector<ovton::msckf::ResidualRecord> make_log(const Planted &p, unsigned seed, int tracks = 2500) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> N(0.0, 1.0);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<ovton::msckf::ResidualRecord> out;
  const int64_t t_base = 1'600'000'000'000'000'000;
  const Eigen::Vector2d f(kFu, kFv), c(kCu, kCv);
  for (int k = 0; k < tracks; ++k) {
    const int len = 4 + static_cast<int>(U(rng) * 7);
    const double t0 = U(rng) * 30.0;
    const Eigen::Vector3d w0(0.35 * N(rng), 0.35 * N(rng), 0.35 * N(rng)), w1(0.9 * N(rng), 0.9 * N(rng), 0.9 * N(rng));
    const auto rate = [&](double s) -> Eigen::Vector3d { return w0 + w1 * s; };
    // Camera rotation since the track's first frame: the body rate integrated in 1 ms steps.
    const auto rotation = [&](double s) {
      Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
      const int steps = std::max(1, static_cast<int>(std::ceil(s / 0.001)));
      const double h = s / steps;
      for (int q = 0; q < steps; ++q)
        R = R * ovton::core::so3_exp(0.5 * (rate(q * h) + rate((q + 1) * h)) * h);
      return R;
    };
    const Eigen::Vector3d P0(-0.55 + 1.1 * U(rng), -0.35 + 0.7 * U(rng), 1.0); // bearing in the first camera frame
    const double depth0 = 1.5 + 3.5 * U(rng);
    const Eigen::Vector3d v0(0.7 * N(rng), 0.7 * N(rng), 0.7 * N(rng)), a0(1.5 * N(rng), 1.5 * N(rng), 1.5 * N(rng));
    const auto image = [&](double s, double &z) { // the camera moves by v0·s + ½·a0·s² in its first frame
      const Eigen::Vector3d P = rotation(s).transpose() * (depth0 * P0 - v0 * s - 0.5 * a0 * s * s);
      z = P.z();
      return Eigen::Vector2d(P.x() / P.z(), P.y() / P.z());
    };
    std::vector<ovton::msckf::ResidualRecord> tr;
    Eigen::VectorXd r(2 * len);
    Eigen::MatrixXd J(2 * len, 3);
    std::vector<Eigen::Vector2d> meas_px(len);
    for (int j = 0; j < len; ++j) {
      const double s = 0.05 * j, t = t0 + s;
      double z = 0, zp = 0, zm = 0;
      const Eigen::Vector2d x = image(s, z);
      const Eigen::Vector2d uv = c + f.cwiseProduct(x);
      const Eigen::Vector2d V = f.cwiseProduct(image(s + 1e-4, zp) - image(s - 1e-4, zm)) / 2e-4;
      const Eigen::Vector2d noise(0.5 * N(rng), 0.5 * N(rng));
      const Eigen::Vector2d meas = uv + noise;
      meas_px[j] = meas;
      Eigen::Vector2d e = noise;
      e += V * (p.td0_s + p.td_rate * t);
      e += V * (uv.y() / kHeight - 0.5) * p.readout_s;
      e += p.focal_eps * (uv - c);
      r.segment<2>(2 * j) = e;
      Eigen::Matrix<double, 2, 3> Jp;
      Jp << kFu / z, 0, -kFu * x.x() / z, 0, kFv / z, -kFv * x.y() / z;
      J.middleRows<2>(2 * j) = Jp * rotation(s).transpose();
      ovton::msckf::ResidualRecord rec;
      rec.update_id = static_cast<uint64_t>(k);
      rec.t_cam_ns = t_base + static_cast<int64_t>(std::llround(t * 1e9));
      rec.feature_id = static_cast<uint64_t>(k);
      rec.obs_index = j;
      rec.track_length = len;
      rec.u_px = meas.x(), rec.v_px = meas.y();
      rec.x_norm = (meas.x() - kCu) / kFu, rec.y_norm = (meas.y() - kCv) / kFv;
      rec.radius_norm = std::hypot(rec.x_norm, rec.y_norm);
      if (j > 0) { // what the filter logs: backward difference, sharing this pixel's noise
        rec.vel_u_px_s = (meas.x() - meas_px[j - 1].x()) / 0.05,
        rec.vel_v_px_s = (meas.y() - meas_px[j - 1].y()) / 0.05;
        rec.vel_source = 1;
      }
      const Eigen::Vector3d w = rate(s);
      rec.w_x = w.x(), rec.w_y = w.y(), rec.w_z = w.z(), rec.w_valid = 1;
      rec.depth_m = z;
      rec.chi2 = 1.0, rec.chi2_threshold = 10.0;
      const bool gated = U(rng) < 0.05;
      rec.status = gated ? ovton::msckf::ResidualStatus::GatedChi2 : ovton::msckf::ResidualStatus::Accepted;
      rec.accepted = gated ? 0 : 1;
      tr.push_back(rec);
    }
    // The triangulated point absorbs the least-squares fit of the residual by a point shift.
    r -= J * J.colPivHouseholderQr().solve(r);
    for (int j = 0; j < len; ++j) {
      tr[j].res_u_px = r(2 * j), tr[j].res_v_px = r(2 * j + 1);
      out.push_back(tr[j]);
    }
  }
  // A few triangulation failures, which must be left out.
  ovton::msckf::ResidualRecord bad = out.front();
  bad.status = ovton::msckf::ResidualStatus::TriangulationFailed;
  bad.res_u_px = bad.res_v_px = ovton::msckf::ResidualRecord::kNaN;
  out.push_back(bad);
  return out;
}

/// The camera of the synthetic logs: pinhole without distortion, camera = body.
CameraCalib synthetic_camera() {
  CameraCalib cam;
  cam.width = 752, cam.height = static_cast<int>(kHeight), cam.rate_hz = 20;
  cam.intrinsics << kFu, kFv, kCu, kCv;
  return cam;
}

DiagnoseReport run(const ovtest::TempDir &dir, const Planted &p, unsigned seed) {
  const std::string file = dir / ("log_" + std::to_string(seed) + ".csv");
  {
    ovton::msckf::ResidualLogWriter w(file);
    w.write(make_log(p, seed));
  }
  DiagnoseOptions opt;
  opt.camera = synthetic_camera();
  opt.have_camera = true;
  return diagnose(load_residual_log(file), opt);
}

} // namespace

TEST(Diagnose, ConstantTimeOffsetRankedFirstAndSized) {
  ovtest::TempDir dir;
  Planted p;
  p.td0_s = 0.008;
  const auto r = run(dir, p, 11);
  ovtest::expect_top(r, "td_const", "offset error δt", 8.0, 1.6);
  std::cout << format_ranking(r);
  EXPECT_EQ(r.rows_triangulation_failed, 1);
  for (const auto &c : r.candidates) {
    if (c.key != "td_const") {
      EXPECT_FALSE(c.explained) << format_ranking(r);
    }
  }
}

TEST(Diagnose, TimeOffsetDriftRankedFirstWithItsRate) {
  ovtest::TempDir dir;
  Planted p;
  p.td0_s = 0.002;
  p.td_rate = 0.0005; // 0.5 ms/s: 2 → 17 ms over the 30 s
  const auto r = run(dir, p, 12);
  ovtest::expect_top(r, "td_drift", "drift rate", 0.5, 0.1);
  ASSERT_GE(r.td_bins.size(), 6u);
  EXPECT_GT(r.td_bins.back().td_ms, r.td_bins.front().td_ms + 8.0); // the per-bin trend shows the drift
}

TEST(Diagnose, RollingShutterReadoutRankedFirstAndSized) {
  ovtest::TempDir dir;
  Planted p;
  p.readout_s = 0.025;
  const auto r = run(dir, p, 13);
  ovtest::expect_top(r, "rolling_shutter", "readout time t_r", 25.0, 5.0);
}

TEST(Diagnose, FocalErrorRankedFirstAndSized) {
  ovtest::TempDir dir;
  Planted p;
  p.focal_eps = 0.01; // δf ≈ 4.6 px
  const auto r = run(dir, p, 14);
  ovtest::expect_top(r, "focal", "relative focal error ε", 1.0, 0.2);
}

TEST(Diagnose, CleanLogFlagsNothingAndWritesReport) {
  ovtest::TempDir dir;
  const auto r = run(dir, Planted{}, 15);
  ovtest::expect_nothing_flagged(r);
  const auto files = write_diagnose_report(r, dir / "out");
  ASSERT_GE(files.size(), 2u);
  EXPECT_TRUE(std::filesystem::exists(dir / "out/diagnose.md"));
  EXPECT_NE(ovtest::read_text(dir / "out/diagnose.json").find("\"top\": null"), std::string::npos);
}

TEST(Diagnose, BadLogsFailWithFileAndLine) {
  ovtest::TempDir dir;
  EXPECT_THROW(load_residual_log(dir / "missing.csv"), DataError);
  const std::string header = ovton::msckf::ResidualLogWriter::header();
  ovton::msckf::ResidualRecord rec;
  rec.res_u_px = rec.res_v_px = 0.1;
  const std::string good = ovton::msckf::ResidualLogWriter::format(rec);

  ovtest::write_text(dir / "wrong_header.csv", "timestamp_ns,px,py,pz\n1,2,3,4\n");
  try {
    load_residual_log(dir / "wrong_header.csv");
    FAIL() << "no error";
  } catch (const DataError &e) {
    EXPECT_EQ(e.line(), 1);
    EXPECT_NE(std::string(e.what()).find("update_id"), std::string::npos) << e.what();
  }
  ovtest::write_text(dir / "no_header.csv", good + "\n");
  EXPECT_THROW(load_residual_log(dir / "no_header.csv"), DataError);

  // An accepted row with a NaN residual (allowed only for triangulation failures), on line 3.
  rec.res_u_px = ovton::msckf::ResidualRecord::kNaN;
  ovtest::write_text(dir / "nan.csv",
                     header + "\n" + good + "\n" + ovton::msckf::ResidualLogWriter::format(rec) + "\n");
  ovtest::expect_data_error([&] { load_residual_log(dir / "nan.csv"); }, "nan.csv", 3, "NaN residual");
  // NaN pixel on line 2.
  rec = ovton::msckf::ResidualRecord{};
  rec.res_u_px = rec.res_v_px = 0.0;
  rec.u_px = ovton::msckf::ResidualRecord::kNaN;
  ovtest::write_text(dir / "nan_px.csv", header + "\n" + ovton::msckf::ResidualLogWriter::format(rec) + "\n");
  ovtest::expect_data_error([&] { load_residual_log(dir / "nan_px.csv"); }, "nan_px.csv", 2, "NaN pixel");
  // A short row and a non-number.
  ovtest::write_text(dir / "short.csv", header + "\n" + good + "\n1,2,3\n");
  ovtest::expect_data_error([&] { load_residual_log(dir / "short.csv"); }, "short.csv", 3, "short row");
  // Too few rows to say anything (a still platform's log holds none): a verdict, every candidate not testable, not an
  // error and not an effect; the report is written.
  ovtest::write_text(dir / "tiny.csv", header + "\n" + good + "\n");
  const DiagnoseReport tiny = diagnose(load_residual_log(dir / "tiny.csv"));
  EXPECT_FALSE(tiny.not_testable.empty());
  ASSERT_EQ(tiny.candidates.size(), ovton::eval::diag::candidate_table().size());
  for (const auto &c : tiny.candidates)
    EXPECT_TRUE(!c.explained && !c.testable) << c.key;
  EXPECT_NE(format_ranking(tiny).find("nothing testable on this log"), std::string::npos) << format_ranking(tiny);
  EXPECT_EQ(write_diagnose_report(tiny, dir / "tiny_diagnose").size(), 2u); // diagnose.md and .json, no plot
}

// The calibration log beside a residual log (the filter's calibration per update): its path, a round trip through
// the writer's format and the reader, and the reader's errors; diagnose's lookup of the row for an image.
TEST(Diagnose, CalibrationLogRoundTripAndLookup) {
  ovtest::TempDir dir;
  EXPECT_EQ(calibration_log_path("a/res.csv"), "a/res_calib.csv");
  EXPECT_EQ(calibration_log_path("a.b/res"), "a.b/res_calib.csv");
  CalibrationLogRow a, b;
  a.update_id = 3, a.t_cam_ns = 1'000'000'000, a.estimated = CalibrationLogRow::kImuIntrinsics;
  a.D_w[8] = 0.97087, a.b_a[1] = -0.0123456789, a.intrinsics[0] = 458.654;
  b = a;
  b.update_id = 4, b.t_cam_ns = 1'050'000'000, b.readout_s = 0.02, b.R_BC[1] = 0.01;
  const std::string file = dir / "res_calib.csv"; // rows without the IMU state (test_diagnose_accel.cpp has them)
  ovtest::write_text(file, calibration_log_header(false) + "\n" + format_calibration_row(a) + "\n" +
                               format_calibration_row(b) + "\n");
  const auto rows = load_calibration_log(file);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1].update_id, 4u);
  EXPECT_EQ(rows[0].estimated, CalibrationLogRow::kImuIntrinsics);
  EXPECT_DOUBLE_EQ(rows[0].D_w[8], 0.97087);
  EXPECT_DOUBLE_EQ(rows[0].b_a[1], -0.0123456789);
  EXPECT_DOUBLE_EQ(rows[1].readout_s, 0.02);
  EXPECT_DOUBLE_EQ(rows[1].R_BC[1], 0.01);
  // The first update at or after an image's time; the last after the end.
  EXPECT_EQ(diag::calibration_at(rows, 900'000'000)->update_id, 3u);
  EXPECT_EQ(diag::calibration_at(rows, 1'000'000'001)->update_id, 4u);
  EXPECT_EQ(diag::calibration_at(rows, 2'000'000'000)->update_id, 4u);
  // Time going back, a short row, a residual log's header.
  ovtest::write_text(dir / "back.csv", calibration_log_header(false) + "\n" + format_calibration_row(b) + "\n" +
                                           format_calibration_row(a) + "\n");
  ovtest::expect_data_error([&] { load_calibration_log(dir / "back.csv"); }, "back.csv", 3, "goes back");
  ovtest::write_text(dir / "short.csv", calibration_log_header(false) + "\n1,2,3\n");
  ovtest::expect_data_error([&] { load_calibration_log(dir / "short.csv"); }, "short.csv", 2, "short row");
  ovtest::write_text(dir / "res.csv", ovton::msckf::ResidualLogWriter::header() + "\n");
  EXPECT_THROW(load_calibration_log(dir / "res.csv"), DataError);
}

// The filter's accelerometer bias absorbs the error of every effect the model lacks, so a candidate tested on it is
// ranked after the selected candidates the images show, with a note, even when its own share is larger; alone it is
// first and carries no such note.
TEST(Diagnose, AccelerometerBiasEvidenceRankedAfterWhatTheImagesShow) {
  const auto &table = diag::candidate_table();
  size_t accel = table.size(), shutter = table.size();
  for (size_t c = 0; c < table.size(); ++c) {
    accel = table[c].key == "accel_scale_axes" ? c : accel;
    shutter = table[c].key == "rolling_shutter" ? c : shutter;
  }
  ASSERT_LT(accel, table.size());
  ASSERT_LT(shutter, table.size());
  std::vector<CandidateResult> res(table.size());
  for (size_t c = 0; c < table.size(); ++c)
    res[c].key = table[c].key;
  res[accel].explained = res[shutter].explained = true;
  res[accel].explained_added = 0.08, res[accel].sigma = 9;
  res[shutter].explained_added = 0.03, res[shutter].sigma = 8;

  const auto both = diag::rank_candidates(res, {accel, shutter});
  EXPECT_EQ(both[0].key, "rolling_shutter");
  EXPECT_EQ(both[1].key, "accel_scale_axes");
  EXPECT_NE(both[1].note.find("re-diagnose after modelling them"), std::string::npos) << both[1].note;

  res[shutter].explained = false;
  const auto alone = diag::rank_candidates(res, {accel});
  EXPECT_EQ(alone[0].key, "accel_scale_axes");
  EXPECT_EQ(alone[0].note, "");
}

// The bar a candidate's Wald statistic must reach (the "not testable" sizes rest on it): the inverse of the σ, larger
// with fewer independent clusters than against χ².
TEST(Diagnose, WaldBarInvertsTheSigmaAndGrowsWithFewClusters) {
  for (int k : {1, 3, 8}) {
    double previous = 0;
    for (double df : {0.0, 40.0, 8.0, 3.0}) {
      const double W = diag::wald_at_sigma(5.0, k, df);
      EXPECT_NEAR(diag::wald_to_sigma(W, k, df), 5.0, 1e-6) << k << " " << df;
      EXPECT_GT(W, previous) << k << " " << df;
      previous = W;
    }
  }
  EXPECT_NEAR(diag::wald_at_sigma(5.0, 1, 0.0), 25.0, 1e-6);
}
