#include "ov_eval/diagnose/accel_design.h"
#include "ov_core/math/so3.h"
#include "ov_eval/diagnose/candidates.h"
#include "ov_eval/diagnose/filter_calibration.h"

#include <Eigen/Geometry>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>

namespace ovton::eval::diag {

namespace {
/// Time constant of the specific force's low pass [s]: how slowly the filter's bias follows it. Chosen on one log
/// (accel scale 3 %, seed 1; docs/diagnose.md): the estimates scale with it (τ 1, 2, 3, 4 s: s_y 1.2, 2.1, 2.9,
/// 3.8 %), the fit's share peaks at 3 s.
constexpr double kTauS = 3.0;
/// A bias bin [s]: the bias's own random walk is removed per bin, as the gyro's on rates.
constexpr double kBinS = 5.0;
} // namespace

namespace {

/// The shortest window of the gravity design [s]: over 0.25-1 s the sizing flights' scale read within 0.4 % (docs/
/// diagnose.md, "Accelerometer scale against gravity"); a longer window averages the attitude's turns, a shorter one
/// has the filter's velocity noise.
constexpr double kWindowS = 0.5; // the message below names it

/// Time constant [s] with which the design's attitude follows the filter's; faster, it follows the gyro. The filter
/// explains part of an accelerometer scale error by tilting (the gravity its bias cannot follow as the body turns), so
/// the tilt of its attitude takes a share of the signal; the gyro does not, but drifts with its own errors. On the
/// sizing flights' 3 % (seeds 1-4) the scale read 2.20-2.59 % through the filter's attitude at every state, 2.67-2.90
/// through the true attitude, 2.32-2.86 with 2 s (0.5 s: 2.17-2.61; 4 s: 2.27-2.86): docs/diagnose.md.
constexpr double kAttitudeTauS = 2.0;

/// One interval between consecutive states: their velocity change, the time, and the accelerometer integrated through
/// the design's attitude, column j = ∫ R(t)·e_j·a_j(t) dt (a through the filter's D_a), and ∫ R(t) dt.
struct Interval {
  double t0 = 0, dt = 0;
  Eigen::Vector3d dv = Eigen::Vector3d::Zero();
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero(), B = Eigen::Matrix3d::Zero();
};

/// Integrates the IMU (through the filter's calibration) between the states of consecutive rows (midpoint rule per
/// reading). The attitude is the gyro's (less the filter's bias), pulled towards the filter's at each row with the time
/// constant kAttitudeTauS (a complementary filter; docs/diagnose.md, "Accelerometer scale against gravity").
std::vector<Interval> intervals(const std::vector<const CalibrationLogRow *> &rows,
                                const std::vector<ovton::core::ImuData> &imu, int64_t t_zero) {
  std::vector<Interval> out;
  size_t i = 0;
  const auto filter_attitude = [](const CalibrationLogRow &r) {
    return Eigen::Quaterniond(r.q_WB[0], r.q_WB[1], r.q_WB[2], r.q_WB[3]).normalized().toRotationMatrix();
  };
  Eigen::Matrix3d R = filter_attitude(*rows.front());
  for (size_t k = 0; k + 1 < rows.size(); ++k) {
    const CalibrationLogRow &a = *rows[k], &b = *rows[k + 1];
    Interval iv;
    iv.t0 = 1e-9 * double(a.t_imu_ns - t_zero);
    iv.dt = 1e-9 * double(b.t_imu_ns - a.t_imu_ns);
    iv.dv = Eigen::Vector3d(b.v_W[0] - a.v_W[0], b.v_W[1] - a.v_W[1], b.v_W[2] - a.v_W[2]);
    if (k > 0) {
      const double pull = std::min(1.0, 1e-9 * double(a.t_imu_ns - rows[k - 1]->t_imu_ns) / kAttitudeTauS);
      const Eigen::AngleAxisd err(filter_attitude(a) * R.transpose()); // world-frame rotation from ours to the filter's
      R = Eigen::AngleAxisd(pull * err.angle(), err.axis()).toRotationMatrix() * R;
    }
    const Eigen::Vector3d bg(a.b_g[0], a.b_g[1], a.b_g[2]);
    while (i > 0 && imu[i].t_imu_ns > a.t_imu_ns)
      --i;
    while (i + 1 < imu.size() && imu[i + 1].t_imu_ns <= a.t_imu_ns)
      ++i;
    int64_t t = a.t_imu_ns;
    // Between readings i and i + 1 the readings are interpolated linearly, at the middle of each piece: a zero-order
    // hold's attitude error, carried over the seconds the attitude follows the gyro, read as 0.1 % of scale on an exact
    // flight (test_diagnose_accel.cpp).
    for (; t < b.t_imu_ns && i < imu.size(); ++i) {
      const bool last = i + 1 >= imu.size();
      const int64_t t_next = std::min(b.t_imu_ns, last ? b.t_imu_ns : imu[i + 1].t_imu_ns);
      const double h = 1e-9 * double(t_next - t);
      if (h > 0) {
        const double span = last ? 1.0 : double(imu[i + 1].t_imu_ns - imu[i].t_imu_ns);
        const double u = last ? 0.0 : (0.5 * double(t + t_next) - double(imu[i].t_imu_ns)) / span;
        const ovton::core::ImuData &n = last ? imu[i] : imu[i + 1];
        const Eigen::Vector3d w = (1 - u) * imu[i].wm + u * n.wm - bg;
        const Eigen::Vector3d am = (1 - u) * imu[i].am + u * n.am;
        const Eigen::Matrix3d Rm = R * ovton::core::so3_exp(0.5 * h * w);
        iv.A += Rm * am.asDiagonal() * h;
        iv.B += Rm * h;
        R = R * ovton::core::so3_exp(h * w);
        t = t_next;
      }
      if (t_next >= b.t_imu_ns)
        break;
    }
    out.push_back(iv);
  }
  return out;
}

/// Projects the columns of N out of every column of X (least squares, QR).
void project_out(const Eigen::MatrixXd &N, Eigen::MatrixXd &X) {
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(N);
  X -= N * qr.solve(X);
}

} // namespace

bool build_accel_gravity_design(const UsedData &data, const DiagnoseOptions &opt, const DiagnoseReport &rep, Design &db,
                                std::string &why) {
  std::vector<const CalibrationLogRow *> rows; // one per state time (the last update's), in the used span
  for (const CalibrationLogRow &c : opt.calibration) {
    if (!c.has_state || c.t_cam_ns < data.t_first || c.t_cam_ns > data.t_last)
      continue;
    if (!rows.empty() && rows.back()->t_imu_ns == c.t_imu_ns)
      rows.back() = &c;
    else if (rows.empty() || c.t_imu_ns > rows.back()->t_imu_ns)
      rows.push_back(&c);
  }
  if (rows.size() < 50) {
    why = "fewer than 50 calibration-log rows with the IMU state in the used span";
    return false;
  }
  if (opt.imu.front().t_imu_ns > rows.front()->t_imu_ns || opt.imu.back().t_imu_ns < rows.back()->t_imu_ns) {
    why = "the IMU does not cover the logged states";
    return false;
  }
  const std::vector<Interval> iv = intervals(rows, imu_through_calibration(opt.imu, opt.calibration), data.t_first);
  // Windows of whole intervals, at least kWindowS long: the rows sum their intervals.
  std::vector<Interval> win;
  Interval cur;
  for (const Interval &x : iv) {
    if (cur.dt == 0)
      cur.t0 = x.t0;
    cur.dt += x.dt, cur.dv += x.dv, cur.A += x.A, cur.B += x.B;
    if (cur.dt >= kWindowS)
      win.push_back(cur), cur = Interval();
  }
  const int nb = std::max(1, static_cast<int>(std::lround(rep.duration_s / kBinS)));
  if (win.size() < 10 || static_cast<int>(win.size()) < 3 * nb) {
    why = "fewer than 10 windows of 0.5 s (or 3 per 5-s bias bin) of the filter's states in the used span";
    return false;
  }
  // r = Σ_j A_j + g·T − Δv = Σ_j β_j·A_j + B·b_bin + λ'·Δv (docs/diagnose.md): β_j = 1 − 1/(1 + s_j) the candidate's,
  // a body-frame bias per bin and the trajectory's own scale (λ' = 1/μ − 1, μ the estimate's size against the truth)
  // the nuisance, projected out of the data and the columns.
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(win.size());
  const Eigen::Vector3d g(0, 0, -opt.gravity_mag);
  Eigen::VectorXd r(n);
  Eigen::MatrixXd X(n, 3), N = Eigen::MatrixXd::Zero(n, 1 + 3 * nb);
  for (size_t w = 0; w < win.size(); ++w) {
    const Interval &x = win[w];
    const int b = std::min(nb - 1, static_cast<int>(nb * x.t0 / std::max(1e-9, rep.duration_s)));
    r.segment<3>(3 * w) = x.A.rowwise().sum() + g * x.dt - x.dv;
    X.block<3, 3>(3 * w, 0) = x.A;
    N.block<3, 1>(3 * w, 0) = x.dv;
    N.block<3, 3>(3 * w, 1 + 3 * b) = x.B;
  }
  Eigen::MatrixXd rx(n, 4);
  rx << r, X;
  project_out(N, rx);
  db.D = Eigen::MatrixXd::Zero(n, kNumCols);
  db.D.col(kAccScale) = rx.rightCols<3>().rowwise().sum();
  db.D.col(kAccAxY) = rx.col(2);
  db.D.col(kAccAxZ) = rx.col(3);
  db.r = rx.col(0);
  db.cluster.resize(n);
  db.t_s.resize(n);
  db.t_mid = 0.5 * rep.duration_s;
  for (Eigen::Index q = 0; q < n; ++q) {
    db.cluster[q] = static_cast<int>(q / 3); // one cluster per window
    db.t_s[q] = win[q / 3].t0;
  }
  db.n_clusters = static_cast<int>(win.size());
  db.accel_against_gravity = true;
  std::vector<double> absr(n);
  for (Eigen::Index q = 0; q < n; ++q)
    absr[q] = std::abs(db.r(q));
  db.scale = std::max(1e-12, 1.4826 * median(absr));
  return true;
}

bool build_accel_design(const UsedData &data, const DiagnoseOptions &opt, const DiagnoseReport &rep, Design &db,
                        std::string &why) {
  if (opt.calibration.empty() || opt.imu.empty()) {
    why = "needs the calibration log beside the residual log and --dataset";
    return false;
  }
  if (std::all_of(opt.calibration.begin(), opt.calibration.end(), [](const auto &c) { return c.has_state; }))
    return build_accel_gravity_design(data, opt, rep, db, why);
  for (const CalibrationLogRow &c : opt.calibration)
    for (int i = 0; i < 9; ++i)
      if (std::abs(c.D_a[i] - opt.calibration.front().D_a[i]) > 1e-9) {
        why = "the filter estimated the accelerometer's scale itself (D_a varies in the calibration log): read its "
              "D_a and sigma instead";
        return false;
      }
  const std::vector<ovton::core::ImuData> imu = imu_through_calibration(opt.imu, opt.calibration);
  struct Sample {
    double t;
    Eigen::Vector3d b, f;
  };
  std::vector<Sample> s;
  Eigen::Vector3d f = imu.front().am;
  size_t k = 0;
  for (const CalibrationLogRow &c : opt.calibration) {
    if (c.t_cam_ns < data.t_first || c.t_cam_ns > data.t_last)
      continue;
    const int64_t t_imu = c.t_cam_ns + static_cast<int64_t>(std::llround(1e9 * c.td_s));
    for (; k < imu.size() && imu[k].t_imu_ns <= t_imu; ++k) { // causal exponential low pass
      const double dt = k ? 1e-9 * double(imu[k].t_imu_ns - imu[k - 1].t_imu_ns) : 0.0;
      const double a = kTauS > 0 ? std::exp(-dt / kTauS) : 0.0;
      f = a * f + (1 - a) * imu[k].am;
    }
    s.push_back({1e-9 * double(c.t_cam_ns - data.t_first), Eigen::Vector3d(c.b_a[0], c.b_a[1], c.b_a[2]), f});
  }
  if (s.size() < 50) {
    why = "fewer than 50 calibration-log rows in the used span";
    return false;
  }
  const int nb = std::max(1, static_cast<int>(std::lround(rep.duration_s / kBinS)));
  const auto bin = [&](double t) {
    return std::min(nb - 1, static_cast<int>(nb * t / std::max(1e-9, rep.duration_s)));
  };
  std::vector<Eigen::Vector3d> sb(nb, Eigen::Vector3d::Zero()), sf(nb, Eigen::Vector3d::Zero());
  std::vector<double> cnt(nb, 0.0);
  for (const Sample &x : s)
    sb[bin(x.t)] += x.b, sf[bin(x.t)] += x.f, cnt[bin(x.t)] += 1;
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(s.size());
  db.D = Eigen::MatrixXd::Zero(n, kNumCols);
  db.r.resize(n);
  db.cluster.resize(n);
  db.t_s.resize(n);
  db.t_mid = 0.5 * rep.duration_s;
  Eigen::Index i = 0;
  for (const Sample &x : s) {
    const int b = bin(x.t);
    for (int a = 0; a < 3; ++a, ++i) {
      db.r(i) = x.b(a) - sb[b](a) / cnt[b];
      db.D(i, a == 0 ? kAccScale : a == 1 ? kAccAxY : kAccAxZ) = x.f(a) - sf[b](a) / cnt[b];
      if (a > 0)
        db.D(i, kAccScale) = db.D(i, a == 1 ? kAccAxY : kAccAxZ);
      db.cluster[i] = static_cast<int>(x.t); // one cluster per second
      db.t_s[i] = x.t;
    }
  }
  db.n_clusters = static_cast<int>(s.back().t) + 1;
  // The bias and the low-passed force are smooth over seconds: neighbouring seconds' scores correlate, up to the low
  // pass's time constant apart (Newey-West over 3 s; with per-second clusters alone a clean plain flight read 5.2σ,
  // with 3 lags 4.0σ; lags 5 and 8 read 4.5σ and 5.3σ there: docs/diagnose.md).
  db.hac_lags = static_cast<int>(kTauS);
  std::vector<double> absr(n);
  for (Eigen::Index q = 0; q < n; ++q)
    absr[q] = std::abs(db.r(q));
  db.scale = std::max(1e-12, 1.4826 * median(absr));
  return true;
}

} // namespace ovton::eval::diag
