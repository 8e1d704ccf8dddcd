#include "ov_sim/imu_synth.h"
#include "ov_core/types/errors.h"
#include "ov_sim/random.h"
#include <cmath>

namespace ovton::sim {

ovton::core::ImuData ideal_imu(const TrajectorySample &s, int64_t t_ns, const Eigen::Vector3d &gravity_W) {
  ovton::core::ImuData m;
  m.t_imu_ns = t_ns;
  m.wm = s.w_B;
  // The accelerometer measures specific force: everything but gravity, in the sensor frame.
  m.am = s.q_WB.toRotationMatrix().transpose() * (s.a_W - gravity_W);
  return m;
}

ImuSynthResult synthesize_imu(const Trajectory &traj, const ImuSynthOptions &opt) {
  const double rate = opt.calib.rate_hz;
  if (!(rate > 0.0))
    throw ovton::core::UsageError("IMU synthesis: rate must be positive");
  const double period_ns_f = 1e9 / rate;
  const double dt = 1.0 / rate;
  const double sig_g = opt.calib.gyro_noise_density * std::sqrt(rate);
  const double sig_a = opt.calib.accel_noise_density * std::sqrt(rate);
  const double sig_bg = opt.calib.gyro_random_walk * std::sqrt(dt);
  const double sig_ba = opt.calib.accel_random_walk * std::sqrt(dt);

  Rng rng(opt.seed);
  ImuSynthResult out;
  Eigen::Vector3d bg = opt.bg0, ba = opt.ba0;
  const int64_t t0 = traj.t_begin_ns(), t1 = traj.t_end_ns();
  for (int64_t k = 0;; ++k) {
    // Stamps from k * period rounded once, so a 200 Hz log never accumulates rounding drift.
    const int64_t t = t0 + static_cast<int64_t>(std::llround(k * period_ns_f));
    if (t > t1)
      break;
    const TrajectorySample s = traj.sample(t);
    ovton::core::ImuData m = ideal_imu(s, t, opt.gravity_W);
    // Draw all six values each step even when a component is off, so toggling one never reshuffles the other.
    Eigen::Vector3d ng, na, wg, wa;
    for (int i = 0; i < 3; ++i)
      ng(i) = rng.normal();
    for (int i = 0; i < 3; ++i)
      na(i) = rng.normal();
    for (int i = 0; i < 3; ++i)
      wg(i) = rng.normal();
    for (int i = 0; i < 3; ++i)
      wa(i) = rng.normal();
    m.wm = (1.0 + opt.gyro_scale) * (m.wm + opt.gyro_M * m.wm) + bg;
    m.am += opt.accel_M * m.am + ba;
    if (opt.add_noise) {
      m.wm += sig_g * ng;
      m.am += sig_a * na;
    }
    ovton::core::StateSample gt = to_state_sample(s, t);
    gt.bg = bg;
    gt.ba = ba;
    out.imu.push_back(m);
    out.truth.push_back(gt);
    if (opt.add_bias_walk) {
      bg += sig_bg * wg;
      ba += sig_ba * wa;
    }
  }
  return out;
}

} // namespace ovton::sim
