// The accelerometer against gravity (ov_eval/diagnose/accel_design.h): on an exact synthetic flight — a turning,
// accelerating body, its IMU at 200 Hz with a planted scale, the filter's states at 20 Hz — the design reads the
// planted scale whatever the trajectory's own size, reads nothing without one or once the filter's D_a has taken it,
// and the calibration log carries the IMU state it needs (older logs still read, without it).
#include "ov_core/io/residual_log_schema.h"
#include "ov_core/types/errors.h"
#include "ov_eval/diagnose/accel_design.h"
#include "ov_eval/diagnose/candidates.h"
#include "ov_eval/diagnose/regression.h"
#include "test_util.h"

#include <Eigen/Geometry>
#include <cmath>

using namespace ovton::core;
using namespace ovton::eval;

namespace {

const Eigen::Vector3d kGravity(0, 0, -9.81);

Eigen::Matrix3d attitude(double t) {
  return (Eigen::AngleAxisd(0.3 * t, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(0.4 * std::sin(1.3 * t + 0.4), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(0.5 * std::sin(0.9 * t), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}
Eigen::Vector3d velocity(double t) {
  return {0.7 * std::cos(0.7 * t), -0.5 * std::sin(0.5 * t), 0.33 * std::cos(1.1 * t)};
}
Eigen::Vector3d acceleration(double t) {
  return {-0.49 * std::sin(0.7 * t), -0.25 * std::cos(0.5 * t), -0.363 * std::sin(1.1 * t)};
}
/// Body rate from the attitude's central difference (exact to ~1e-9 rad/s here).
Eigen::Vector3d body_rate(double t) {
  const double h = 1e-5;
  const Eigen::AngleAxisd d(attitude(t - h).transpose() * attitude(t + h));
  return d.angle() * d.axis() / (2 * h);
}

struct Flight {
  std::vector<ImuData> imu;
  std::vector<CalibrationLogRow> rows;
  diag::UsedData data;
  DiagnoseReport rep;
};

/// 30 s: the accelerometer reads diag(1 + s)·Rᵀ(a − g) + b_a, the gyro the rate + b_g; the filter's states every 50 ms
/// with the true attitude and the velocity times `traj_scale` (a monocular estimate's own size).
Flight make_flight(const Eigen::Vector3d &s, double traj_scale) {
  Flight f;
  const int64_t t0 = 1'000'000'000;
  const Eigen::Vector3d ba(0.05, -0.08, 0.12), bg(0.002, -0.001, 0.003);
  for (int i = 0; i <= 200 * 30; ++i) {
    const double t = 0.005 * i;
    ImuData m;
    m.t_imu_ns = t0 + 5'000'000LL * i;
    m.am = (Eigen::Vector3d::Ones() + s).asDiagonal() * (attitude(t).transpose() * (acceleration(t) - kGravity)) + ba;
    m.wm = body_rate(t) + bg;
    f.imu.push_back(m);
  }
  for (int k = 0; k <= 20 * 29; ++k) {
    const double t = 0.5 + 0.05 * k;
    CalibrationLogRow r;
    r.update_id = k;
    r.t_cam_ns = r.t_imu_ns = t0 + 50'000'000LL * k + 500'000'000LL;
    r.has_state = true;
    const Eigen::Quaterniond q(attitude(t));
    r.q_WB[0] = q.w(), r.q_WB[1] = q.x(), r.q_WB[2] = q.y(), r.q_WB[3] = q.z();
    for (int a = 0; a < 3; ++a)
      r.v_W[a] = traj_scale * velocity(t)(a), r.b_g[a] = bg(a);
    f.rows.push_back(r);
  }
  f.data.t_first = f.rows.front().t_cam_ns;
  f.data.t_last = f.rows.back().t_cam_ns;
  f.rep.duration_s = 1e-9 * double(f.data.t_last - f.data.t_first);
  return f;
}

/// The scale the design reads with the candidate's columns (s from β = 1 − 1/(1 + s)).
std::vector<double> read_scale(const Flight &f, const std::vector<int> &cols) {
  DiagnoseOptions opt;
  opt.imu = f.imu;
  opt.calibration = f.rows;
  diag::Design d;
  std::string why;
  EXPECT_TRUE(diag::build_accel_design(f.data, opt, f.rep, d, why)) << why;
  EXPECT_TRUE(d.accel_against_gravity);
  const diag::Fit fit = diag::fit_cols(d, cols, 3.0);
  std::vector<double> s;
  for (Eigen::Index i = 0; i < fit.beta.size(); ++i) {
    const double beta = i == 0 ? fit.beta(0) : fit.beta(0) + fit.beta(i); // the axes' columns add to the first
    s.push_back(beta / (1 - beta));
  }
  return s;
}

} // namespace

TEST(DiagnoseAccel, ScaleReadAgainstGravityWhateverTheTrajectorysOwnSize) {
  for (double traj_scale : {1.0, 1.04, 0.97}) {
    const Flight f = make_flight(Eigen::Vector3d::Constant(0.03), traj_scale);
    const auto s = read_scale(f, {diag::kAccScale});
    EXPECT_NEAR(s[0], 0.03, 2e-5) << "trajectory scale " << traj_scale;
  }
  const auto none = read_scale(make_flight(Eigen::Vector3d::Zero(), 1.03), {diag::kAccScale});
  EXPECT_NEAR(none[0], 0.0, 2e-5);
}

TEST(DiagnoseAccel, PerAxisScaleRead) {
  const Flight f = make_flight(Eigen::Vector3d(0.01, 0.02, 0.04), 1.02);
  const auto s = read_scale(f, {diag::kAccScale, diag::kAccAxY, diag::kAccAxZ});
  ASSERT_EQ(s.size(), 3u);
  EXPECT_NEAR(s[0], 0.01, 2e-5);
  EXPECT_NEAR(s[1], 0.02, 2e-5);
  EXPECT_NEAR(s[2], 0.04, 2e-5);
}

// The filter that estimated the scale (its D_a in the calibration log) leaves nothing to read.
TEST(DiagnoseAccel, ScaleTheFilterEstimatedIsNotReadAgain) {
  Flight f = make_flight(Eigen::Vector3d::Constant(0.03), 1.0);
  for (CalibrationLogRow &r : f.rows)
    r.D_a[0] = r.D_a[4] = r.D_a[8] = 1 / 1.03;
  EXPECT_NEAR(read_scale(f, {diag::kAccScale})[0], 0.0, 2e-5);
}

// Without the IMU state (a log written before the columns existed) the design on the filter's bias is used; too few
// rows, and the design says why instead of reading.
TEST(DiagnoseAccel, FallsBackOrSaysWhy) {
  Flight f = make_flight(Eigen::Vector3d::Constant(0.03), 1.0);
  DiagnoseOptions opt;
  opt.imu = f.imu;
  opt.calibration = f.rows;
  for (CalibrationLogRow &r : opt.calibration)
    r.has_state = false;
  diag::Design d;
  std::string why;
  EXPECT_TRUE(diag::build_accel_design(f.data, opt, f.rep, d, why)) << why;
  EXPECT_FALSE(d.accel_against_gravity);
  opt.calibration.assign(f.rows.begin(), f.rows.begin() + 40);
  EXPECT_FALSE(diag::build_accel_gravity_design(f.data, opt, f.rep, d, why));
  EXPECT_NE(why.find("fewer than 50"), std::string::npos) << why;
}

// The calibration log with the IMU state: a round trip, a log without those columns still read (has_state false),
// and a quaternion that is not a unit one named with its line.
TEST(DiagnoseAccel, CalibrationLogCarriesTheImuState) {
  ovtest::TempDir dir;
  const Flight f = make_flight(Eigen::Vector3d::Zero(), 1.0);
  std::string with = calibration_log_header(true) + "\n", without = calibration_log_header(false) + "\n";
  for (int k = 0; k < 3; ++k) {
    with += format_calibration_row(f.rows[k]) + "\n";
    CalibrationLogRow old = f.rows[k];
    old.has_state = false;
    without += format_calibration_row(old) + "\n";
  }
  ovtest::write_text(dir / "with.csv", with);
  ovtest::write_text(dir / "without.csv", without);
  const auto a = load_calibration_log(dir / "with.csv");
  ASSERT_EQ(a.size(), 3u);
  EXPECT_TRUE(a[2].has_state);
  EXPECT_EQ(a[2].t_imu_ns, f.rows[2].t_imu_ns);
  for (int i = 0; i < 4; ++i)
    EXPECT_NEAR(a[2].q_WB[i], f.rows[2].q_WB[i], 1e-9);
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(a[2].v_W[i], f.rows[2].v_W[i], 1e-9);
  const auto b = load_calibration_log(dir / "without.csv");
  ASSERT_EQ(b.size(), 3u);
  EXPECT_FALSE(b[0].has_state);
  CalibrationLogRow bad = f.rows[0];
  bad.q_WB[0] *= 1.01;
  ovtest::write_text(dir / "bad.csv", calibration_log_header(true) + "\n" + format_calibration_row(bad) + "\n");
  ovtest::expect_data_error([&] { load_calibration_log(dir / "bad.csv"); }, "bad.csv", 2, "unit quaternion");
}
