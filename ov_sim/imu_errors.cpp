#include "ov_sim/imu_errors.h"
#include "ov_core/types/errors.h"
#include "ov_sim/random.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <opencv2/core.hpp>
#include <sstream>

namespace ovton::sim {

void drop_imu_error_parts(ImuErrorModel &m, const std::string &parts) {
  std::istringstream list(parts);
  for (std::string p; std::getline(list, p, ',');) {
    const auto drop_bands = [&](double lo, double hi) { // bands lying within [lo, hi) Hz
      m.flight_spectrum.erase(std::remove_if(m.flight_spectrum.begin(), m.flight_spectrum.end(),
                                             [&](const NoiseBand &b) { return b.low_hz >= lo && b.high_hz <= hi; }),
                              m.flight_spectrum.end());
    };
    if (p == "scale")
      m.gyro_scale_misalignment.setIdentity();
    else if (p == "turn-on")
      m.gyro_bias0.setZero(), m.accel_bias0.setZero();
    else if (p == "slow")
      drop_bands(0.0, 2.0);
    else if (p == "mid")
      drop_bands(2.0, 10.0);
    else if (p == "vibration")
      drop_bands(10.0, 1e9);
    else if (p == "vibration-gyro" || p == "vibration-accel") {
      for (NoiseBand &b : m.flight_spectrum)
        if (b.low_hz >= 10.0)
          (p == "vibration-gyro" ? b.gyro : b.accel).setZero();
    } else
      throw ovton::core::UsageError("unknown IMU error part '" + p +
                                    "' (scale, turn-on, slow, mid, vibration, vibration-gyro, vibration-accel)");
  }
}

void check(const ImuErrorModel &m) {
  const auto need = [](bool ok, const char *what) {
    if (!ok)
      throw ovton::core::UsageError(std::string("IMU error model: ") + what);
  };
  need(m.gyro_scale_misalignment.allFinite() && std::abs(m.gyro_scale_misalignment.determinant() - 1.0) < 0.5,
       "gyro scale/misalignment must be finite and near identity");
  need(m.ground_gyro_ratio >= 0 && m.ground_accel_ratio >= 0, "ground noise ratios must be >= 0");
  for (size_t i = 0; i < m.flight_spectrum.size(); ++i) {
    const NoiseBand &b = m.flight_spectrum[i];
    need(b.low_hz >= 0 && b.high_hz > b.low_hz, "spectrum bands need 0 <= low < high");
    need(i == 0 || b.low_hz >= m.flight_spectrum[i - 1].high_hz, "spectrum bands must be ordered, not overlapping");
    need((b.gyro.array() >= 0).all() && (b.accel.array() >= 0).all(), "spectrum densities must be >= 0");
  }
}

namespace {

/// One axis of Gaussian noise with a piecewise-constant one-sided PSD `psd(f)` [unit^2/Hz], n samples at fs, by
/// synthesis in the frequency domain: X_k = sqrt(n fs S(f_k) / 2) (a + i b) / sqrt(2), Hermitian, inverse DFT.
std::vector<double> coloured_noise(size_t n, double fs, const std::function<double(double)> &psd, Rng &rng) {
  const int N = cv::getOptimalDFTSize(static_cast<int>(n));
  cv::Mat spec(N, 1, CV_64FC2, cv::Scalar(0, 0));
  for (int k = 1; k <= N / 2; ++k) {
    const double f = static_cast<double>(k) * fs / N;
    const double a = rng.normal(), b = rng.normal(); // drawn for every bin, so the spectrum never reshuffles them
    const double amp = std::sqrt(std::max(0.0, psd(f)) * N * fs / 2.0 / 2.0);
    cv::Vec2d &X = spec.at<cv::Vec2d>(k);
    X = cv::Vec2d(amp * a, amp * b);
    if (k == N - k) // Nyquist bin of an even length: real
      X = cv::Vec2d(amp * a * std::sqrt(2.0), 0.0);
    else
      spec.at<cv::Vec2d>(N - k) = cv::Vec2d(X[0], -X[1]);
  }
  cv::Mat x;
  cv::dft(spec, x, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);
  std::vector<double> out(n);
  for (size_t i = 0; i < n; ++i)
    out[i] = x.at<double>(static_cast<int>(i));
  return out;
}

} // namespace

void add_imu_errors(const Trajectory &traj, const ImuErrorModel &m, double white_gyro, double white_accel,
                    uint64_t seed, std::vector<ovton::core::ImuData> &imu,
                    std::vector<ovton::core::StateSample> &truth) {
  check(m);
  if (!m.enabled || imu.size() < 2)
    return;
  if (truth.size() != imu.size())
    throw ovton::core::UsageError("IMU errors: the log and its truth differ in length");
  const size_t n = imu.size();
  const double fs = (n - 1) / ((imu.back().t_imu_ns - imu.front().t_imu_ns) * 1e-9);
  Rng rng(seed);

  // In flight wherever the speed exceeds the threshold within +-2 s (a multicopter hovers now and then; its rotors
  // run up before take-off and after landing).
  std::vector<char> moving(n), flying(n);
  for (size_t i = 0; i < n; ++i)
    moving[i] = traj.sample(imu[i].t_imu_ns).v_W.norm() > m.flight_speed_mps;
  const size_t reach = static_cast<size_t>(std::lround(2.0 * fs));
  for (size_t i = 0; i < n; ++i) { // `moving` dilated by `reach` samples on both sides
    const size_t lo = i > reach ? i - reach : 0, hi = std::min(n - 1, i + reach);
    flying[i] = std::any_of(moving.begin() + lo, moving.begin() + hi + 1, [](char c) { return c != 0; });
  }

  // Coloured noise per axis: the measured spectrum minus the white noise already in the log.
  const auto band_psd = [&](bool gyro, int axis, double f) {
    if (m.flight_spectrum.empty())
      return 0.0;
    double d = 0.0;
    if (f < m.flight_spectrum.front().low_hz) {
      d = gyro ? m.flight_spectrum.front().gyro(axis) : m.flight_spectrum.front().accel(axis);
    } else {
      for (const NoiseBand &b : m.flight_spectrum)
        if (f >= b.low_hz && f < b.high_hz)
          d = gyro ? b.gyro(axis) : b.accel(axis);
    }
    const double white = gyro ? white_gyro : white_accel;
    return std::max(0.0, d * d - white * white);
  };
  std::vector<double> noise[6];
  for (int c = 0; c < 6; ++c)
    noise[c] = coloured_noise(
        n, fs, [&](double f) { return band_psd(c < 3, c % 3, f); }, rng);

  const Eigen::Matrix3d S = m.gyro_scale_misalignment;
  for (size_t i = 0; i < n; ++i) {
    ovton::core::ImuData &d = imu[i];
    ovton::core::StateSample &t = truth[i];
    // The log holds w + b + white noise (w scaled by a planted gyro scale, if any): the misalignment applies to
    // what is not bias (its effect on the white noise, a few 1e-3 of it, is immaterial).
    const Eigen::Vector3d w_meas_rest = d.wm - t.bg;
    const Eigen::Vector3d gyro_ratio_scale = Eigen::Vector3d::Constant(flying[i] ? 1.0 : m.ground_gyro_ratio);
    const Eigen::Vector3d accel_ratio_scale = Eigen::Vector3d::Constant(flying[i] ? 1.0 : m.ground_accel_ratio);
    const Eigen::Vector3d ng(noise[0][i], noise[1][i], noise[2][i]), na(noise[3][i], noise[4][i], noise[5][i]);
    d.wm = S * w_meas_rest + t.bg + m.gyro_bias0 + gyro_ratio_scale.cwiseProduct(ng);
    d.am += m.accel_bias0 + accel_ratio_scale.cwiseProduct(na);
    // The truth's bias is the slowly varying part the filter can estimate: datasheet walk plus turn-on bias. The
    // coloured noise's wander below 0.2 Hz is noise to the filter's model, and stays out of the truth.
    t.bg += m.gyro_bias0;
    t.ba += m.accel_bias0;
  }
}

double allan_variance(const ImuErrorModel &m, bool gyro, int axis, double white, double walk, double tau_s,
                      double rate_hz) {
  // AVAR(tau) = 4 * integral of S(f) sin^4(pi f tau) / (pi f tau)^2 df over [0, f_max] (S the two-sided level, as
  // sensor.yaml's white noise sigma: AVAR = sigma^2 / tau), plus walk^2 tau / 3 for the bias random walk. S is
  // piecewise constant; the integral runs on a log grid from 1e-5 Hz to the top band (or 100 Hz), 2000 points per
  // decade, with sin^4 replaced by its mean 3/8 where a step spans more than a quarter of its period 1/tau. The means
  // are of samples at rate_hz (the boxcar's response k sin(pi f / rate) in place of pi f tau: it matters near Nyquist).
  const double f_max = rate_hz / 2;
  const auto density2 = [&](double f) {
    double d = 0.0;
    if (m.enabled && !m.flight_spectrum.empty()) {
      const NoiseBand &first = m.flight_spectrum.front();
      if (f < first.low_hz)
        d = gyro ? first.gyro(axis) : first.accel(axis);
      for (const NoiseBand &b : m.flight_spectrum)
        if (f >= b.low_hz && f < b.high_hz)
          d = gyro ? b.gyro(axis) : b.accel(axis);
    }
    // The bands are one-sided densities (as imu_match measures them and coloured_noise() draws them: variance =
    // integral of d^2 over [0, fs/2]); sensor.yaml's white noise w has the two-sided level w^2. The log carries
    // w plus the coloured part max(0, d^2 - w^2) (add_imu_errors), i.e. the two-sided level w^2 + that / 2.
    return white * white + 0.5 * std::max(0.0, d * d - white * white);
  };
  const double f0 = 1e-5, decades = std::log10(f_max / f0);
  const int n = static_cast<int>(decades * 2000);
  double avar = 0.0;
  for (int i = 0; i < n; ++i) {
    const double fa = f0 * std::pow(10.0, decades * i / n), fb = f0 * std::pow(10.0, decades * (i + 1) / n);
    const double f = 0.5 * (fa + fb), s = std::sin(M_PI * f * tau_s);
    const double s4 = (fb - fa) * tau_s > 0.25 ? 3.0 / 8.0 : s * s * s * s;
    const double x = tau_s * rate_hz * std::sin(M_PI * f / rate_hz); // pi f tau for f << rate: a sampled log's mean
    avar += 4.0 * density2(f) * s4 / (x * x) * (fb - fa);
  }
  return avar + walk * walk * tau_s / 3.0;
}

ovton::core::ImuCalib fitted_imu_noise(const ImuErrorModel &m, const ovton::core::ImuCalib &datasheet, double tau_min_s,
                                       double tau_max_s) {
  if (!(tau_min_s > 0 && tau_max_s > tau_min_s))
    throw ovton::core::UsageError("fitted_imu_noise: need 0 < tau_min < tau_max");
  // AVAR(tau) ~ N^2 / tau + K^2 tau / 3, fitted by least squares on log AVAR at 25 averaging times spaced evenly in
  // log tau (every decade weighs alike; over- and under-declaring by the same factor cost alike): a grid search over
  // log N^2 and log K^2 (K^2 down to 1e-6 of the level that would explain everything), refined three times.
  const auto fit = [&](bool gyro, double white, double walk, double &N, double &K) {
    const int n_tau = 25;
    std::vector<double> tau(n_tau), log_a(n_tau);
    for (int i = 0; i < n_tau; ++i) {
      tau[i] = tau_min_s * std::pow(tau_max_s / tau_min_s, static_cast<double>(i) / (n_tau - 1));
      double a = 0.0;
      for (int axis = 0; axis < 3; ++axis)
        a += allan_variance(m, gyro, axis, white, walk, tau[i], datasheet.rate_hz) / 3.0;
      log_a[i] = std::log(a);
    }
    const auto cost = [&](double ln_n2, double ln_k2) {
      double c = 0.0;
      for (int i = 0; i < n_tau; ++i) {
        const double e = std::log(std::exp(ln_n2) / tau[i] + std::exp(ln_k2) * tau[i] / 3.0) - log_a[i];
        c += e * e;
      }
      return c;
    };
    double best_n = log_a[0] + std::log(tau[0]), best_k = log_a[n_tau - 1] - std::log(tau[n_tau - 1] / 3.0);
    double span = 16.0; // +-16 in ln (about 7 decades)
    for (int round = 0; round < 4; ++round, span /= 8.0) {
      const double cn = best_n, ck = best_k;
      double best_c = cost(cn, ck);
      for (int a = -40; a <= 40; ++a)
        for (int b = -40; b <= 40; ++b) {
          const double ln_n2 = cn + span * a / 40.0, ln_k2 = ck + span * b / 40.0, c = cost(ln_n2, ln_k2);
          if (c < best_c)
            best_c = c, best_n = ln_n2, best_k = ln_k2;
        }
    }
    N = std::sqrt(std::exp(best_n));
    K = std::sqrt(std::exp(best_k));
  };
  ovton::core::ImuCalib out = datasheet;
  fit(true, datasheet.gyro_noise_density, datasheet.gyro_random_walk, out.gyro_noise_density, out.gyro_random_walk);
  fit(false, datasheet.accel_noise_density, datasheet.accel_random_walk, out.accel_noise_density,
      out.accel_random_walk);
  return out;
}

ImuErrorModel euroc_v1_01_imu_errors() {
  // Measured by `ovton simulate --match-imu` on ../shared/data/euroc_v1_01_moving (the full 145 s V1_01 imu0 log):
  // against EuRoC's own ground truth (state_groundtruth_estimate0, knots 0.1 s) for alignment, biases and the bands
  // below 2 Hz and above 20 Hz, against the 200 Hz euroc_groundtruth/V1_01_easy.txt with knots 0.03 s for 2-20 Hz
  // (where the coarser fit leaves real motion in the residual). docs/simulate.md lists both reports.
  ImuErrorModel m;
  m.enabled = true;
  m.gyro_scale_misalignment << 1.000416, 0.000140, 0.000850, 0.000140, 1.001328, 0.000143, 0.000850, 0.000143, 1.002562;
  m.gyro_bias0 = Eigen::Vector3d(-0.00216, 0.0211, 0.0765);
  m.accel_bias0 = Eigen::Vector3d(-0.025, 0.145, 0.079);
  // Below 2 Hz the residual keeps rising towards 0 Hz (bias wander): the 0.1-0.2 Hz level is held down to 0 Hz. A
  // synthetic V1_01 log's 10-s means then scatter by (0.0005, 0.0004, 0.0010) rad/s and (0.013, 0.018, 0.017) m/s^2,
  // the real log's by (0.00056, 0.00045, 0.00081) and (0.010, 0.030, 0.012).
  const auto band = [](double lo, double hi, Eigen::Vector3d g, Eigen::Vector3d a) { return NoiseBand{lo, hi, g, a}; };
  m.flight_spectrum = {
      band(0.1, 0.2, {0.0018, 0.0017, 0.0034}, {0.035, 0.060, 0.024}),
      band(0.2, 0.5, {0.0012, 0.0010, 0.0015}, {0.028, 0.024, 0.026}),
      band(0.5, 2.0, {0.00050, 0.00069, 0.00071}, {0.0194, 0.0132, 0.0157}),
      band(2.0, 10.0, {0.00006, 0.00015, 0.00010}, {0.0011, 0.0013, 0.0010}),
      band(10.0, 20.0, {0.0013, 0.0043, 0.0030}, {0.049, 0.018, 0.022}),
      band(20.0, 40.0, {0.0033, 0.0022, 0.0027}, {0.054, 0.060, 0.036}),
      band(40.0, 60.0, {0.00062, 0.0013, 0.00085}, {0.059, 0.027, 0.040}),
      band(60.0, 100.0, {0.0015, 0.0061, 0.0030}, {0.153, 0.063, 0.121}),
  };
  // 20-90 Hz on the ground with idle rotors against in flight: gyro (0.0020, 0.0025, 0.0013) / (0.0020, 0.0033,
  // 0.0022), accel (0.050, 0.035, 0.024) / (0.088, 0.053, 0.060).
  m.ground_gyro_ratio = 0.77;
  m.ground_accel_ratio = 0.55;
  return m;
}

} // namespace ovton::sim
