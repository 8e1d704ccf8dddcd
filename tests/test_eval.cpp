// Trajectory metrics: association, alignment, APE/ARE/RPE, TPE (paper eq. 16), CIT (eq. 15).
#include "ov_core/types/errors.h"
#include "ov_eval/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

using namespace ovton::core;
using namespace ovton::eval;

namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Quaterniond rpy(double roll, double pitch, double yaw) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
}

/// A helix with a wobbling attitude, 20 Hz for 30 s: non-planar, so SE(3) alignment is fully determined.
std::vector<StateSample> helix() {
  std::vector<StateSample> v;
  for (int k = 0; k < 600; ++k) {
    const double t = 0.05 * k;
    StateSample s;
    s.t_ns = 1'000'000'000'000'000'000LL + static_cast<int64_t>(k) * 50'000'000;
    s.p = Eigen::Vector3d(2.0 * std::cos(0.4 * t), 2.0 * std::sin(0.4 * t), 0.05 * t + 0.3 * std::sin(0.7 * t));
    s.q_WB = rpy(0.1 * std::sin(t), 0.05 * std::cos(0.5 * t), 0.4 * t + M_PI / 2);
    v.push_back(s);
  }
  return v;
}

/// The EuRoC ground-truth text files: `t[s] tx ty tz qx qy qz qw`. Seconds are split at the dot so that
/// nanosecond stamps stay exact (a double holds only ~16 digits of 1.4e18 ns).
std::vector<StateSample> load_euroc_txt(const std::string &file) {
  std::vector<StateSample> v;
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#')
      continue;
    std::istringstream ss(line);
    std::string t;
    double x, y, z, qx, qy, qz, qw;
    ss >> t >> x >> y >> z >> qx >> qy >> qz >> qw;
    const auto dot = t.find('.');
    std::string frac = dot == std::string::npos ? "" : t.substr(dot + 1);
    frac.resize(9, '0');
    StateSample s;
    s.t_ns = std::stoll(t.substr(0, dot)) * 1'000'000'000LL + std::stoll(frac);
    s.p = Eigen::Vector3d(x, y, z);
    s.q_WB = Eigen::Quaterniond(qw, qx, qy, qz).normalized();
    v.push_back(s);
  }
  return v;
}

/// The estimate a perfect VIO would report in a world frame related to truth's by gt.p = R * est.p + t.
std::vector<StateSample> move(const std::vector<StateSample> &gt, const Eigen::Quaterniond &q,
                              const Eigen::Vector3d &t) {
  std::vector<StateSample> est = gt;
  for (StateSample &s : est) {
    s.p = q.conjugate() * (s.p - t);
    s.q_WB = q.conjugate() * s.q_WB;
  }
  return est;
}

EvalOptions opts(AlignMode m) {
  EvalOptions o;
  o.align = m;
  return o;
}

// Shared body of the alignment tests, run on synthetic and on real EuRoC truth.
void check_alignment(const std::vector<StateSample> &gt) {
  {
    // A monocular VIO's typical failure: the trajectory 4 % too large (and in another frame). Sim3 finds the scale
    // exactly and removes the error; SE3 cannot.
    auto est = move(gt, rpy(5.0 * kDeg, 2.0 * kDeg, -70.0 * kDeg), Eigen::Vector3d(1.0, 2.0, -0.5));
    for (StateSample &s : est)
      s.p *= 1.04;
    const EvalResult sim3 = evaluate(est, gt, {}, opts(AlignMode::Sim3));
    EXPECT_NEAR(sim3.alignment.s, 1.0 / 1.04, 1e-12);
    EXPECT_LT(sim3.ape_rmse_m, 1e-9);
    EXPECT_GT(evaluate(est, gt, {}, opts(AlignMode::SE3)).ape_rmse_m, 1e-3);
  }
  const Eigen::Vector3d t(3.0, -7.5, 1.25);
  {
    const auto est = move(gt, rpy(0, 0, 37.0 * kDeg), t);
    const EvalResult r = evaluate(est, gt, {}, opts(AlignMode::PosYaw));
    EXPECT_EQ(r.n_matched, static_cast<int>(gt.size()));
    EXPECT_LT(r.ape_rmse_m, 1e-9);
    EXPECT_LT(r.ape_max_m, 1e-9);
    EXPECT_LT(r.are_rmse_deg, 1e-6);
    EXPECT_NEAR(std::atan2(r.alignment.R(1, 0), r.alignment.R(0, 0)), 37.0 * kDeg, 1e-12);
    EXPECT_LT((r.alignment.t - t).norm(), 1e-9);
  }
  {
    const auto est = move(gt, rpy(10.0 * kDeg, -6.0 * kDeg, 120.0 * kDeg), t);
    const EvalResult se3 = evaluate(est, gt, {}, opts(AlignMode::SE3));
    EXPECT_LT(se3.ape_rmse_m, 1e-9);
    EXPECT_LT(se3.are_rmse_deg, 1e-6);
    EXPECT_TRUE(se3.alignment.R.isApprox(rpy(10.0 * kDeg, -6.0 * kDeg, 120.0 * kDeg).toRotationMatrix(), 1e-12));
    EXPECT_EQ(se3.alignment.s, 1.0);
    const EvalResult py = evaluate(est, gt, {}, opts(AlignMode::PosYaw));
    EXPECT_GT(py.ape_rmse_m, 0.01) << "a yaw-only fit cannot undo roll and pitch";
    EXPECT_GT(py.are_rmse_deg, 1.0);
    // Relative errors do not depend on the world frame at all.
    for (const RpeResult &rr : se3.rpe) {
      if (rr.count > 0) {
        EXPECT_LT(rr.trans_rmse_m, 1e-9);
        EXPECT_LT(rr.rot_rmse_deg, 1e-6);
      }
    }
  }
}

std::string euroc_file(const std::string &name) {
  return std::string(OVTON_SOURCE_DIR) + "/../shared/data/euroc_groundtruth/" + name;
}

} // namespace

TEST(EvalAlign, ParseModes) {
  EXPECT_EQ(parse_align_mode("posyaw"), AlignMode::PosYaw);
  EXPECT_EQ(parse_align_mode("se3"), AlignMode::SE3);
  EXPECT_EQ(parse_align_mode("none"), AlignMode::None);
  EXPECT_EQ(parse_align_mode("sim3"), AlignMode::Sim3);
  EXPECT_STREQ(to_string(AlignMode::SE3), "se3");
  EXPECT_STREQ(to_string(AlignMode::Sim3), "sim3");
  EXPECT_THROW(parse_align_mode("sim(3)"), UsageError);
}

TEST(EvalAlign, SyntheticHelixRecoversPosYawAndSE3) {
  check_alignment(helix());
}

TEST(EvalAlign, RealEurocV102RecoversPosYawAndSE3) {
  const std::string file = euroc_file("V1_02_medium.txt");
  if (!std::ifstream(file))
    GTEST_SKIP() << "reference data not found: " << file << " (../shared/data is not part of a fresh clone)";
  const auto gt = load_euroc_txt(file);
  ASSERT_GT(gt.size(), 10000u);
  check_alignment(gt);
}

TEST(EvalAlign, ReflectionIsNotReturnedForPlanarData) {
  // Planar points make the cross-covariance rank 2: the SVD may pick a reflection, which must be fixed.
  auto gt = helix();
  for (auto &s : gt)
    s.p.z() = 0.0;
  const auto est = move(gt, rpy(0, 0, 0.3), Eigen::Vector3d(1, 2, 3));
  Association a = associate(est, gt);
  const Alignment al = align(a, AlignMode::SE3);
  EXPECT_NEAR(al.R.determinant(), 1.0, 1e-12);
  for (size_t i = 0; i < a.est.size(); ++i)
    EXPECT_LT((al.R * a.est[i].p + al.t - a.gt[i].p).norm(), 1e-9);
}

TEST(EvalApe, PlantedOffsetsAreReportedExactly) {
  const auto gt = helix();
  auto est = gt;
  for (auto &s : est)
    s.p.x() += 0.1;
  const EvalResult r = evaluate(est, gt, {}, opts(AlignMode::None));
  EXPECT_NEAR(r.ape_rmse_m, 0.1, 1e-12);
  EXPECT_NEAR(r.ape_mean_m, 0.1, 1e-12);
  EXPECT_NEAR(r.ape_max_m, 0.1, 1e-12);
  EXPECT_NEAR(r.are_rmse_deg, 0.0, 1e-6);
  ASSERT_EQ(r.ape_per_pose_m.size(), gt.size());
  // A constant position offset leaves body-frame relative motion intact.
  for (const RpeResult &rr : r.rpe) {
    if (rr.count > 0) {
      EXPECT_LT(rr.trans_rmse_m, 1e-9);
    }
  }

  // Rotation error on the body side and on the world side: both are 2 degrees.
  auto est_b = gt, est_w = gt;
  for (size_t i = 0; i < gt.size(); ++i) {
    est_b[i].q_WB = gt[i].q_WB * Eigen::AngleAxisd(2.0 * kDeg, Eigen::Vector3d(1, 2, 3).normalized());
    est_w[i].q_WB = Eigen::AngleAxisd(2.0 * kDeg, Eigen::Vector3d::UnitY()) * gt[i].q_WB;
  }
  const EvalResult rb = evaluate(est_b, gt, {}, opts(AlignMode::None));
  EXPECT_NEAR(rb.are_rmse_deg, 2.0, 1e-9);
  EXPECT_NEAR(rb.ape_rmse_m, 0.0, 1e-12);
  EXPECT_NEAR(evaluate(est_w, gt, {}, opts(AlignMode::None)).are_rmse_deg, 2.0, 1e-9);
}

TEST(EvalRpe, StraightLineWithScaleErrorByHand) {
  // Truth moves 0.25 m per sample along x (exact in binary); the estimate moves 10% too far.
  std::vector<StateSample> gt, est;
  for (int k = 0; k < 41; ++k) {
    StateSample s;
    s.t_ns = k * 100'000'000LL;
    s.p = Eigen::Vector3d(0.25 * k, 0, 0);
    gt.push_back(s);
    s.p.x() *= 1.1;
    est.push_back(s);
  }
  EvalOptions o = opts(AlignMode::None);
  o.rpe_segments_m = {1.0, 4.0, 100.0};
  const EvalResult r = evaluate(est, gt, {}, o);
  ASSERT_EQ(r.rpe.size(), 3u);
  EXPECT_EQ(r.rpe[0].count, 41 - 4);
  EXPECT_NEAR(r.rpe[0].trans_rmse_m, 0.1, 1e-12);
  EXPECT_NEAR(r.rpe[0].rot_rmse_deg, 0.0, 1e-12);
  EXPECT_EQ(r.rpe[1].count, 41 - 16);
  EXPECT_NEAR(r.rpe[1].trans_rmse_m, 0.4, 1e-12);
  EXPECT_EQ(r.rpe[2].count, 0);
  EXPECT_TRUE(std::isnan(r.rpe[2].trans_rmse_m));
}

TEST(EvalAssociate, InterpolatesPositionAndSlerpsOrientation) {
  std::vector<StateSample> gt(3);
  for (int k = 0; k < 3; ++k) {
    gt[k].t_ns = k * 1'000'000'000LL;
    gt[k].p = Eigen::Vector3d(k, 2 * k, 0);
    gt[k].q_WB = Eigen::AngleAxisd(0.8 * k, Eigen::Vector3d::UnitZ());
  }
  std::vector<StateSample> est(3);
  est[0].t_ns = 250'000'000;   // inside
  est[1].t_ns = 2'000'000'000; // exactly on the last truth sample
  est[2].t_ns = 2'000'000'001; // past the truth: dropped
  const Association a = associate(est, gt, 1.5);
  ASSERT_EQ(a.gt.size(), 2u);
  EXPECT_TRUE(a.gt[0].p.isApprox(Eigen::Vector3d(0.25, 0.5, 0)));
  EXPECT_NEAR(a.gt[0].q_WB.angularDistance(Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()))), 0.0,
              1e-12);
  EXPECT_EQ(a.gt[0].t_ns, est[0].t_ns);
  EXPECT_TRUE(a.gt[1].p.isApprox(gt[2].p));
}

TEST(EvalAssociate, DropsEstimatesInTruthGaps) {
  std::vector<StateSample> gt(3), est(2);
  gt[0].t_ns = 0;
  gt[1].t_ns = 1'000'000'000;
  gt[2].t_ns = 1'500'000'000;
  est[0].t_ns = 500'000'000;   // inside a 1 s gap
  est[1].t_ns = 1'200'000'000; // inside a 0.5 s interval
  const Association a = associate(est, gt, 0.6);
  ASSERT_EQ(a.est.size(), 1u);
  EXPECT_EQ(a.est[0].t_ns, est[1].t_ns);
}

TEST(EvalAssociate, EmptyOrDisjointInputsThrowClearly) {
  const auto gt = helix();
  EXPECT_THROW(associate({}, gt), UsageError);
  EXPECT_THROW(associate(gt, {}), UsageError);
  auto later = gt;
  for (auto &s : later)
    s.t_ns += 3600LL * 1'000'000'000LL;
  try {
    evaluate(later, gt, {}, EvalOptions{});
    FAIL() << "expected UsageError";
  } catch (const UsageError &e) {
    EXPECT_NE(std::string(e.what()).find("no estimate stamp falls inside the ground truth"), std::string::npos)
        << e.what();
  }
  auto unsorted = gt;
  std::swap(unsorted[3], unsorted[4]);
  EXPECT_THROW(associate(gt, unsorted), UsageError);
}

TEST(EvalApe, PositionOnlyTruth) {
  auto gt = helix();
  for (auto &s : gt)
    s.has_orientation = false; // RTK-style truth
  const Eigen::Vector3d t(1, 2, 3);
  const auto est = move(gt, rpy(0, 0, 1.0), t);
  for (AlignMode m : {AlignMode::PosYaw, AlignMode::SE3}) {
    const EvalResult r = evaluate(est, gt, {}, opts(m));
    EXPECT_LT(r.ape_rmse_m, 1e-9);
    EXPECT_TRUE(std::isnan(r.are_rmse_deg));
    ASSERT_FALSE(r.rpe.empty());
    EXPECT_GT(r.rpe[0].count, 0);
    EXPECT_LT(r.rpe[0].trans_rmse_m, 1e-9);
    EXPECT_TRUE(std::isnan(r.rpe[0].rot_rmse_deg));
  }
}

namespace {

/// Three frames at t_imu = 1, 2, 3 s moving at (3, 4, 0) m/s; truth td(t_cam) = 10 ms + 1 ms/s * t_cam.
std::vector<StateSample> tpe_estimate(bool with_velocity) {
  const double td_hat[3] = {0.020, 0.015, 0.012};
  std::vector<StateSample> est(3);
  for (int k = 0; k < 3; ++k) {
    est[k].t_ns = (k + 1) * 1'000'000'000LL;
    est[k].p = Eigen::Vector3d(3.0, 4.0, 0.0) * (k + 1);
    est[k].v = Eigen::Vector3d(3.0, 4.0, 0.0);
    est[k].has_velocity = with_velocity;
    est[k].td_s = td_hat[k];
    est[k].has_td = true;
  }
  return est;
}

std::vector<TdSample> linear_td_truth() {
  std::vector<TdSample> td;
  for (int k = 0; k <= 5; ++k)
    td.push_back({k * 1'000'000'000LL, 0.010 + 0.001 * k});
  return td;
}

} // namespace

TEST(EvalTpe, HandComputedCase) {
  // Truth looked up at t_cam = t_imu - td_hat: 0.98, 1.985, 2.988 s -> 10.98, 11.985, 12.988 ms.
  // TPE = (td_hat - td_gt) * 5 m/s = 45.1, 15.075, -4.94 mm.
  const double expected = std::sqrt((45.1 * 45.1 + 15.075 * 15.075 + 4.94 * 4.94) / 3.0);
  const auto gt = tpe_estimate(true);
  for (bool with_velocity : {true, false}) { // finite differences are exact on a straight constant-speed path
    const EvalResult r = evaluate(tpe_estimate(with_velocity), gt, linear_td_truth(), opts(AlignMode::None));
    ASSERT_TRUE(r.has_tpe);
    EXPECT_EQ(r.tpe_count, 3);
    EXPECT_NEAR(r.tpe_rmse_mm, expected, 1e-9);
  }
  // No truth: no TPE. No td in the estimate: neither TPE nor CIT.
  EXPECT_FALSE(evaluate(tpe_estimate(true), gt, {}, opts(AlignMode::None)).has_tpe);
  auto no_td = tpe_estimate(true);
  for (auto &s : no_td)
    s.has_td = false;
  const EvalResult r = evaluate(no_td, gt, linear_td_truth(), opts(AlignMode::None));
  EXPECT_FALSE(r.has_tpe);
  EXPECT_FALSE(r.has_cit);
}

TEST(EvalTpe, TruthIsClampedOutsideItsSpan) {
  auto est = tpe_estimate(true);
  for (auto &s : est)
    s.td_s = 0.0;
  const std::vector<TdSample> td = {{1'500'000'000, 0.004}, {1'600'000'000, 0.002}};
  // Frames at 1 s and 3 s fall outside: 4 ms and 2 ms; frame at 2 s as well (2 ms). Speed 5 m/s.
  const double expected = std::sqrt((20.0 * 20.0 + 10.0 * 10.0 + 10.0 * 10.0) / 3.0);
  EXPECT_NEAR(evaluate(est, est, td, opts(AlignMode::None)).tpe_rmse_mm, expected, 1e-9);
}

namespace {

std::vector<StateSample> cit_estimate(const std::vector<double> &td) {
  std::vector<StateSample> est(td.size());
  for (size_t k = 0; k < td.size(); ++k) {
    est[k].t_ns = static_cast<int64_t>(k) * 50'000'000LL;
    est[k].p = Eigen::Vector3d(0.1 * k, 0, 0);
    est[k].td_s = td[k];
    est[k].has_td = true;
  }
  return est;
}

} // namespace

TEST(EvalCit, HandComputedCase) {
  // k=1: 5 ms off. k=2: within eps1 but moved 4.5 ms. k=3: moved 0.7 ms. k=4: moved 0.15 ms. k=5: converged.
  const auto est = cit_estimate({0.0, 0.005, 0.0095, 0.0102, 0.01005, 0.01001, 0.01});
  EvalOptions o = opts(AlignMode::None);
  o.cit.eps1_s = 1e-3;
  o.cit.eps2_s = 1e-4;
  o.cit.target_from_truth = false;
  o.cit.target_s = 0.010;
  EvalResult r = evaluate(est, est, {}, o);
  EXPECT_TRUE(r.has_cit);
  EXPECT_EQ(r.cit, 5);

  // The same with the target read from a constant truth file.
  o.cit.target_from_truth = true;
  r = evaluate(est, est, {{0, 0.010}}, o);
  EXPECT_TRUE(r.has_cit);
  EXPECT_EQ(r.cit, 5);

  // A truth target far from the estimate: never converges.
  r = evaluate(est, est, {{0, 0.030}}, o);
  EXPECT_EQ(r.cit, -1);

  // Truth target requested but no truth: skipped rather than silently compared with 0.
  EXPECT_FALSE(evaluate(est, est, {}, o).has_cit);

  // Frame 0 never counts, even when it already sits on the target.
  o.cit.target_from_truth = false;
  EXPECT_EQ(evaluate(cit_estimate({0.01, 0.01}), cit_estimate({0.01, 0.01}), {}, o).cit, 1);
}

TEST(EvalAlign, StillTrajectoryTakesYawFromOrientations) {
  // A platform that does not move: positions cannot fix yaw, orientations can.
  std::vector<ovton::core::StateSample> gt, est;
  const Eigen::Matrix3d Rz = Eigen::AngleAxisd(1.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (int i = 0; i < 50; ++i) {
    ovton::core::StateSample g;
    g.t_ns = 1000000000LL + i * 50000000LL;
    g.p = Eigen::Vector3d(1.0, 2.0, 0.5) + 1e-4 * Eigen::Vector3d(std::sin(i), std::cos(i), 0);
    g.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 1, 0).normalized()));
    ovton::core::StateSample e = g;
    e.p = Rz.transpose() * g.p;
    e.q_WB = Eigen::Quaterniond(Rz.transpose() * g.q_WB.toRotationMatrix());
    gt.push_back(g);
    est.push_back(e);
  }
  ovton::eval::EvalOptions opt;
  const auto r = ovton::eval::evaluate(est, gt, {}, opt);
  EXPECT_LT(r.ape_rmse_m, 1e-9);
  EXPECT_LT(r.are_rmse_deg, 1e-6);
}
