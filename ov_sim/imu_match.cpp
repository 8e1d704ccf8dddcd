#include "ov_sim/imu_match.h"
#include "ov_core/math/so3.h"
#include "ov_core/types/errors.h"
#include "ov_sim/imu_synth.h"
#include "ov_sim/trajectory.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numeric>

namespace ovton::sim {

namespace {

constexpr double kGravity = 9.81; // as the synthetic IMU (imu_synth.h); a gravity error lands in the accel scale

struct GtAt {
  Eigen::Vector3d w, f; ///< ideal gyro and specific force in the ground truth's body frame
  Eigen::Matrix3d R_BW; ///< for the world tilt's columns
  double speed = 0, rate = 0;
};

GtAt gt_at(const Trajectory &traj, int64_t t) {
  const TrajectorySample s = traj.sample(t);
  const ovton::core::ImuData m = ideal_imu(s, t, Eigen::Vector3d(0, 0, -kGravity));
  GtAt g;
  g.w = m.wm;
  g.f = m.am;
  g.R_BW = s.q_WB.toRotationMatrix().transpose();
  g.speed = s.v_W.norm();
  g.rate = s.w_B.norm();
  return g;
}

/// Per-axis least squares y_k = A_k x + b_k; returns the residual sum of squares and fills A, b.
double fit_affine(const std::vector<Eigen::Vector3d> &x, const std::vector<Eigen::Vector3d> &y, Eigen::Matrix3d &A,
                  Eigen::Vector3d &b) {
  Eigen::Matrix4d N = Eigen::Matrix4d::Zero();
  Eigen::Matrix<double, 4, 3> r = Eigen::Matrix<double, 4, 3>::Zero();
  for (size_t i = 0; i < x.size(); ++i) {
    Eigen::Vector4d h;
    h << x[i], 1.0;
    N += h * h.transpose();
    r += h * y[i].transpose();
  }
  const Eigen::Matrix<double, 4, 3> P = N.ldlt().solve(r);
  A = P.topRows<3>().transpose();
  b = P.row(3).transpose();
  double rss = 0.0;
  for (size_t i = 0; i < x.size(); ++i)
    rss += (y[i] - A * x[i] - b).squaredNorm();
  return rss;
}

/// A = R S with R a rotation and S symmetric positive definite (polar decomposition by SVD).
void polar(const Eigen::Matrix3d &A, Eigen::Matrix3d &R, Eigen::Matrix3d &S) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  R = svd.matrixU() * svd.matrixV().transpose();
  S = svd.matrixV() * svd.singularValues().asDiagonal() * svd.matrixV().transpose();
}

Eigen::Vector3d rotation_vector(const Eigen::Matrix3d &R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

/// Welch estimate of the one-sided PSD of each axis of r over segments of n samples lying wholly where `in` holds
/// (Hann window, half overlap); returns the white-equivalent density sqrt(mean PSD) over [f_lo, f_hi].
BandDensity band_density(const std::vector<Eigen::Vector3d> &r, const std::vector<bool> &in, double fs, double f_lo,
                         double f_hi) {
  // Segments long enough for 4 periods of the band's lowest frequency (at least 256 samples).
  int n = 256;
  while (n < 4.0 * fs / std::max(f_lo, 1e-3) && n < (1 << 16))
    n *= 2;
  BandDensity out;
  out.low_hz = f_lo;
  out.high_hz = f_hi;
  std::vector<double> w(n);
  double w2 = 0.0;
  for (int i = 0; i < n; ++i) {
    w[i] = 0.5 - 0.5 * std::cos(2.0 * M_PI * i / n);
    w2 += w[i] * w[i];
  }
  const int k_lo = static_cast<int>(std::ceil(f_lo * n / fs)), k_hi = static_cast<int>(std::floor(f_hi * n / fs));
  Eigen::Vector3d acc = Eigen::Vector3d::Zero();
  size_t segments = 0;
  for (size_t s = 0; s + n <= r.size(); s += n / 2) {
    bool ok = true;
    for (int i = 0; i < n && ok; ++i)
      ok = in[s + i];
    if (!ok)
      continue;
    ++segments;
    for (int a = 0; a < 3; ++a) {
      double mean = 0.0;
      for (int i = 0; i < n; ++i)
        mean += r[s + i](a);
      mean /= n;
      for (int k = k_lo; k <= k_hi; ++k) {
        std::complex<double> X(0.0, 0.0);
        for (int i = 0; i < n; ++i)
          X += w[i] * (r[s + i](a) - mean) * std::polar(1.0, -2.0 * M_PI * k * i / n);
        acc(a) += 2.0 * std::norm(X) / (fs * w2) / (k_hi - k_lo + 1);
      }
    }
  }
  out.samples = segments * n / 2;
  if (segments > 0)
    out.density = (acc / static_cast<double>(segments)).cwiseSqrt();
  return out;
}

} // namespace

ImuMatchReport match_imu(const std::vector<ovton::core::ImuData> &imu, const std::vector<ovton::core::StateSample> &gt,
                         const ImuMatchOptions &opt) {
  if (imu.size() < 100 || gt.size() < 10)
    throw ovton::core::UsageError("IMU matching needs an IMU log and a ground truth");
  const int64_t margin = ovton::core::s_to_ns(opt.max_shift_s + 0.5);
  const int64_t t0 = std::max(imu.front().t_imu_ns, gt.front().t_ns) + margin;
  const int64_t t1 = std::min(imu.back().t_imu_ns, gt.back().t_ns) - margin;
  if (t1 - t0 < ovton::core::s_to_ns(20.0))
    throw ovton::core::UsageError("the IMU log and the ground truth overlap by less than 20 s");
  const SplineTrajectory traj(gt, t0 - margin, t1 + margin, opt.knot_dt_s, "imu match");
  std::vector<const ovton::core::ImuData *> used;
  for (const auto &m : imu)
    if (m.t_imu_ns >= t0 && m.t_imu_ns <= t1)
      used.push_back(&m);
  ImuMatchReport rep;
  rep.samples = used.size();
  rep.duration_s = (used.back()->t_imu_ns - used.front()->t_imu_ns) * 1e-9;
  const double fs = (used.size() - 1) / rep.duration_s;
  {
    double s = 0, s2 = 0;
    for (size_t i = 1; i < used.size(); ++i) {
      const double dt = (used[i]->t_imu_ns - used[i - 1]->t_imu_ns) * 1e-9;
      s += dt;
      s2 += dt * dt;
    }
    const double n = static_cast<double>(used.size() - 1);
    rep.imu_dt_jitter_s = std::sqrt(std::max(0.0, s2 / n - (s / n) * (s / n)));
  }
  std::vector<Eigen::Vector3d> wm(used.size()), am(used.size());
  for (size_t i = 0; i < used.size(); ++i) {
    wm[i] = used[i]->wm;
    am[i] = used[i]->am;
  }

  // The ground truth's time shift: the one under which an affine map explains the gyro best (rotation is sharp in
  // time; the gyro's scale, axes and bias are free in the fit, so they cannot bias the shift).
  std::vector<Eigen::Vector3d> wg(used.size());
  const auto gyro_rss = [&](double shift) {
    const int64_t d = ovton::core::s_to_ns(shift);
    for (size_t i = 0; i < used.size(); ++i)
      wg[i] = gt_at(traj, used[i]->t_imu_ns + d).w;
    Eigen::Matrix3d A;
    Eigen::Vector3d b;
    return fit_affine(wg, wm, A, b);
  };
  double best = 0.0, best_rss = std::numeric_limits<double>::infinity();
  for (double s = -opt.max_shift_s; s <= opt.max_shift_s + 1e-12; s += 0.002) {
    const double rss = gyro_rss(s);
    if (rss < best_rss)
      best_rss = rss, best = s;
  }
  for (double step = 0.001; step >= 0.000125; step /= 2) { // refine by halving around the best
    for (const double s : {best - step, best + step}) {
      const double rss = gyro_rss(s);
      if (rss < best_rss)
        best_rss = rss, best = s;
    }
  }
  rep.gt_shift_s = best;

  // Final fits at that shift.
  const int64_t d = ovton::core::s_to_ns(best);
  std::vector<GtAt> g(used.size());
  for (size_t i = 0; i < used.size(); ++i) {
    g[i] = gt_at(traj, used[i]->t_imu_ns + d);
    wg[i] = g[i].w;
  }
  Eigen::Matrix3d Ag;
  Eigen::Vector3d bg;
  fit_affine(wg, wm, Ag, bg);
  Eigen::Matrix3d Rg;
  polar(Ag, Rg, rep.gyro_S);
  rep.gyro_rotation = rotation_vector(Rg);
  rep.gyro_bias = bg;
  // The gyro fit is well conditioned in every axis (the body turns about all three): its rotation is the ground
  // truth's body frame against the IMU's axes, and the accelerometer is taken to share it.
  rep.gt_rotation = rep.gyro_rotation;
  // A multicopter's specific force stays along its thrust axis, so in the body frame the accelerometer sees little
  // but gravity along one axis: its scale and axes cannot be told from a bias and the ground truth's own error (a
  // free affine fit shrinks the horizontal scales by regression dilution, to 0.76 on V1_01). Fit what the data
  // separate, bias and the world's tilt, with unit scale; report how much each axis' true signal varies.
  Eigen::Matrix<double, 5, 1> xa;
  const auto accel_fit = [&](double shift) {
    const int64_t da = ovton::core::s_to_ns(shift);
    Eigen::Matrix<double, 5, 5> N = Eigen::Matrix<double, 5, 5>::Zero();
    Eigen::Matrix<double, 5, 1> rhs = Eigen::Matrix<double, 5, 1>::Zero();
    double yy = 0.0;
    for (size_t i = 0; i < used.size(); ++i) {
      const GtAt gi = gt_at(traj, used[i]->t_imu_ns + da);
      const Eigen::Matrix3d R_IW = Rg * gi.R_BW;
      Eigen::Matrix<double, 3, 5> H;
      H.block<3, 3>(0, 0) = Eigen::Matrix3d::Identity();
      // Tilt (dx, dy) of the world against gravity adds R_IW (g dy, -g dx, 0) to the specific force.
      H.col(3) = -kGravity * R_IW.col(1);
      H.col(4) = kGravity * R_IW.col(0);
      const Eigen::Vector3d y = am[i] - Rg * gi.f;
      N += H.transpose() * H;
      rhs += H.transpose() * y;
      yy += y.squaredNorm();
    }
    xa = N.ldlt().solve(rhs);
    return yy - xa.dot(rhs); // residual sum of squares at the least-squares solution
  };
  // The accelerometer's own delay against the gyro (an IMU's internal filtering may differ between its sensors).
  double best_a = best, best_a_rss = std::numeric_limits<double>::infinity();
  for (double sft = best - 0.02; sft <= best + 0.02 + 1e-12; sft += 0.002) {
    const double rss = accel_fit(sft);
    if (rss < best_a_rss)
      best_a_rss = rss, best_a = sft;
  }
  rep.accel_delay_s = best_a - best;
  accel_fit(best_a);
  rep.accel_bias = xa.segment<3>(0);
  rep.gt_tilt = xa.segment<2>(3);
  Eigen::Vector3d f_mean = Eigen::Vector3d::Zero(), f_sq = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < used.size(); ++i) {
    const GtAt ga = gt_at(traj, used[i]->t_imu_ns + ovton::core::s_to_ns(best_a));
    g[i].f = Rg * ga.f; // from here on in the IMU's axes
    g[i].R_BW = Rg * ga.R_BW;
    f_mean += g[i].f;
    f_sq += g[i].f.cwiseAbs2();
  }
  f_mean /= static_cast<double>(used.size());
  rep.accel_signal_std = (f_sq / static_cast<double>(used.size()) - f_mean.cwiseAbs2()).cwiseMax(0.0).cwiseSqrt();

  std::vector<Eigen::Vector3d> rg(used.size()), ra(used.size());
  std::vector<bool> still(used.size()), flight(used.size());
  for (size_t i = 0; i < used.size(); ++i) {
    rg[i] = wm[i] - Ag * g[i].w - bg;
    const Eigen::Vector3d tilt_f =
        g[i].R_BW * Eigen::Vector3d(kGravity * rep.gt_tilt.y(), -kGravity * rep.gt_tilt.x(), 0.0);
    ra[i] = am[i] - g[i].f - rep.accel_bias - tilt_f;
    still[i] = g[i].speed < opt.still_speed_mps && g[i].rate < opt.still_rate_rps;
    flight[i] = g[i].speed > opt.flight_speed_mps;
    rep.gyro_fit_rms += rg[i].cwiseAbs2();
    rep.accel_fit_rms += ra[i].cwiseAbs2();
  }
  // A multicopter hovers now and then: in flight from 2 s before it first moves faster than flight_speed until 2 s
  // after it last does (as imu_errors.h decides it), still only outside that and at rest.
  {
    const size_t reach = static_cast<size_t>(2.0 * fs);
    std::vector<bool> moving = flight;
    for (size_t i = 0; i < used.size(); ++i) {
      const size_t lo = i > reach ? i - reach : 0, hi = std::min(used.size() - 1, i + reach);
      flight[i] = std::find(moving.begin() + lo, moving.begin() + hi + 1, true) != moving.begin() + hi + 1;
      still[i] = still[i] && !flight[i];
    }
  }
  rep.gyro_fit_rms = (rep.gyro_fit_rms / used.size()).cwiseSqrt();
  rep.accel_fit_rms = (rep.accel_fit_rms / used.size()).cwiseSqrt();
  const double f_hi = 0.45 * fs;
  rep.gyro_still = band_density(rg, still, fs, opt.high_band_hz, f_hi);
  rep.accel_still = band_density(ra, still, fs, opt.high_band_hz, f_hi);
  rep.gyro_flight = band_density(rg, flight, fs, opt.high_band_hz, f_hi);
  rep.accel_flight = band_density(ra, flight, fs, opt.high_band_hz, f_hi);
  for (const auto &[lo, hi] : std::vector<std::pair<double, double>>{{0.05, 0.2},
                                                                     {0.2, 0.5},
                                                                     {0.5, 2.0},
                                                                     {2.0, 5.0},
                                                                     {5.0, 10.0},
                                                                     {10.0, 20.0},
                                                                     {20.0, 40.0},
                                                                     {40.0, 60.0},
                                                                     {60.0, 0.49 * fs}}) {
    rep.gyro_flight_spectrum.push_back(band_density(rg, flight, fs, lo, hi));
    rep.accel_flight_spectrum.push_back(band_density(ra, flight, fs, lo, hi));
  }

  // Slow changes: means of the residual over 10-s blocks (std about the constant bias), and the correlation time
  // of 1-s means of the gyro residual.
  const auto block_means = [&](const std::vector<Eigen::Vector3d> &r, double block_s) {
    std::vector<Eigen::Vector3d> m;
    const size_t n = static_cast<size_t>(block_s * fs);
    for (size_t s = 0; s + n <= r.size(); s += n)
      m.push_back(std::accumulate(r.begin() + s, r.begin() + s + n, Eigen::Vector3d::Zero().eval()) / n);
    return m;
  };
  const auto spread = [](const std::vector<Eigen::Vector3d> &m) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero(), var = Eigen::Vector3d::Zero();
    for (const auto &x : m)
      mean += x;
    mean /= static_cast<double>(m.size());
    for (const auto &x : m)
      var += (x - mean).cwiseAbs2();
    return (var / static_cast<double>(std::max<size_t>(1, m.size() - 1))).cwiseSqrt().eval();
  };
  rep.gyro_bias_drift = spread(block_means(rg, 10.0));
  rep.accel_bias_drift = spread(block_means(ra, 10.0));
  {
    const auto m = block_means(rg, 1.0);
    std::vector<double> x(m.size());
    for (size_t i = 0; i < m.size(); ++i)
      x[i] = m[i].sum();
    const double mean = std::accumulate(x.begin(), x.end(), 0.0) / x.size();
    double c0 = 0.0;
    for (double v : x)
      c0 += (v - mean) * (v - mean);
    rep.bias_correlation_s = static_cast<double>(x.size());
    for (size_t lag = 1; lag < x.size() / 2; ++lag) {
      double c = 0.0;
      for (size_t i = 0; i + lag < x.size(); ++i)
        c += (x[i] - mean) * (x[i + lag] - mean);
      if (c / c0 < std::exp(-1.0)) {
        rep.bias_correlation_s = static_cast<double>(lag);
        break;
      }
    }
  }
  return rep;
}

std::string imu_match_yaml(const ImuMatchReport &r) {
  std::string s;
  char b[512];
  const auto v3 = [&](const char *key, const Eigen::Vector3d &v, double scale = 1.0) {
    std::snprintf(b, sizeof(b), "  %s: [%.6g, %.6g, %.6g]\n", key, v.x() * scale, v.y() * scale, v.z() * scale);
    s += b;
  };
  const auto m3 = [&](const char *key, const Eigen::Matrix3d &m) {
    std::snprintf(b, sizeof(b), "  %s: [[%.6f, %.6f, %.6f], [%.6f, %.6f, %.6f], [%.6f, %.6f, %.6f]]\n", key, m(0, 0),
                  m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2), m(2, 0), m(2, 1), m(2, 2));
    s += b;
  };
  const auto band = [&](const char *key, const BandDensity &d) {
    std::snprintf(b, sizeof(b), "  %s: {density: [%.4g, %.4g, %.4g], band_hz: [%.0f, %.0f], samples: %zu}\n", key,
                  d.density.x(), d.density.y(), d.density.z(), d.low_hz, d.high_hz, d.samples);
    s += b;
  };
  std::snprintf(b, sizeof(b), "samples: %zu\nduration_s: %.2f\nimu_dt_jitter_s: %.3g\n", r.samples, r.duration_s,
                r.imu_dt_jitter_s);
  s += b;
  s += "ground_truth:  # the reference's own errors, not the IMU's\n";
  std::snprintf(b, sizeof(b), "  time_shift_ms: %.3f  # the IMU reading at t matches the ground truth at t + shift\n",
                r.gt_shift_s * 1e3);
  s += b;
  v3("body_to_imu_rotation_deg", r.gt_rotation, 180.0 / M_PI);
  std::snprintf(b, sizeof(b), "  accel_delay_ms: %.3f  # the accelerometer's own shift against the gyro (IMU)\n",
                r.accel_delay_s * 1e3);
  s += b;
  std::snprintf(b, sizeof(b), "  world_tilt_deg: [%.4f, %.4f]\n", r.gt_tilt.x() * 180.0 / M_PI,
                r.gt_tilt.y() * 180.0 / M_PI);
  s += b;
  s += "imu:  # what the synthetic IMU should carry\n";
  m3("gyro_scale_misalignment", r.gyro_S);
  v3("gyro_fit_rotation_deg", r.gyro_rotation, 180.0 / M_PI);
  v3("accel_signal_std_m_s2", r.accel_signal_std);
  v3("gyro_bias_rad_s", r.gyro_bias);
  v3("accel_bias_m_s2", r.accel_bias);
  v3("gyro_bias_drift_rad_s", r.gyro_bias_drift);
  v3("accel_bias_drift_m_s2", r.accel_bias_drift);
  std::snprintf(b, sizeof(b), "  bias_correlation_s: %.1f\n", r.bias_correlation_s);
  s += b;
  band("gyro_noise_still_rad_s_sqrtHz", r.gyro_still);
  band("accel_noise_still_m_s2_sqrtHz", r.accel_still);
  band("gyro_noise_flight_rad_s_sqrtHz", r.gyro_flight);
  band("accel_noise_flight_m_s2_sqrtHz", r.accel_flight);
  s += "  flight_spectrum:  # white-equivalent density per band: gyro [rad/s/sqrt(Hz)], accel [m/s^2/sqrt(Hz)]\n";
  for (size_t i = 0; i < r.gyro_flight_spectrum.size(); ++i) {
    const auto &g = r.gyro_flight_spectrum[i], &a = r.accel_flight_spectrum[i];
    std::snprintf(b, sizeof(b), "    - {band_hz: [%.1f, %.1f], gyro: [%.4g, %.4g, %.4g], accel: [%.4g, %.4g, %.4g]}\n",
                  g.low_hz, g.high_hz, g.density.x(), g.density.y(), g.density.z(), a.density.x(), a.density.y(),
                  a.density.z());
    s += b;
  }
  v3("gyro_fit_rms_rad_s", r.gyro_fit_rms);
  v3("accel_fit_rms_m_s2", r.accel_fit_rms);
  return s;
}

} // namespace ovton::sim
