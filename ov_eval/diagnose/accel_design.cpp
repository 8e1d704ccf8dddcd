#include "ov_eval/diagnose/accel_design.h"
#include "ov_eval/diagnose/candidates.h"
#include "ov_eval/diagnose/filter_calibration.h"

#include <algorithm>
#include <cmath>

namespace ov_eval::diag {

namespace {
/// Time constant of the specific force's low pass [s]: how slowly the filter's bias follows it. Chosen on one log
/// (accel scale 3 %, seed 1; docs/diagnose.md): the estimates scale with it (τ 1, 2, 3, 4 s: s_y 1.2, 2.1, 2.9,
/// 3.8 %), the fit's share peaks at 3 s.
constexpr double kTauS = 3.0;
/// A bias bin [s]: the bias's own random walk is removed per bin, as the gyro's on rates.
constexpr double kBinS = 5.0;
} // namespace

bool build_accel_design(const UsedData &data, const DiagnoseOptions &opt, const DiagnoseReport &rep, Design &db,
                        std::string &why) {
  if (opt.calibration.empty() || opt.imu.empty()) {
    why = "needs the calibration log beside the residual log and --dataset";
    return false;
  }
  for (const CalibrationLogRow &c : opt.calibration)
    for (int i = 0; i < 9; ++i)
      if (std::abs(c.D_a[i] - opt.calibration.front().D_a[i]) > 1e-9) {
        why = "the filter estimated the accelerometer's scale itself (D_a varies in the calibration log): read its "
              "D_a and sigma instead";
        return false;
      }
  const std::vector<ov_core::ImuData> imu = imu_through_calibration(opt.imu, opt.calibration);
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
      db.D(i, kAccAx0 + a) = x.f(a) - sf[b](a) / cnt[b];
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

} // namespace ov_eval::diag
