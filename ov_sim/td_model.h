#pragma once
// Camera-IMU time-offset models for simulation and perturbation. Convention: t_imu = t_cam + t_d.
// The paper (TON-VIO eq. 3-4) writes t_cam = t_imu + t_d; its drift model is the same recursion with our sign.
#include "ov_core/types/sensor_data.h"
#include <cstdint>
#include <string>
#include <vector>

namespace ovton::sim {

enum class TdModelKind { Constant, Drift, Wander };

TdModelKind
parse_td_model(const std::string &name); ///< "constant" | "drift" | "wander"; throws ovton::core::UsageError
std::string to_string(TdModelKind k);

struct TdModelOptions {
  TdModelKind kind = TdModelKind::Constant;
  double td0_s = 0.010;             ///< offset at the first image
  double bias_s_per_s = 1e-4;       ///< drift: deterministic growth per second (scaled to each frame interval)
  double noise_s_per_sqrt_s = 1e-4; ///< drift: random-walk density, step sigma = this * sqrt(frame interval)
  /// wander: back and forth without a trend, td(t) = td0 + A·sin(2π·t/P), t from the first image (what a camera
  /// whose clock is disciplined to the IMU's by a slow control loop does; the mean over whole periods is td0).
  double wander_amplitude_s = 0.004;
  double wander_period_s = 10.0;
  uint64_t seed = 0;
};

/// One image: the IMU-clock instant it shows, its camera-clock stamp and the offset between them.
struct TimedImage {
  int64_t t_imu_ns = 0; ///< true instant the scene was captured (IMU clock)
  int64_t t_cam_ns = 0; ///< stamp written to cam0/data.csv
  int64_t td_ns = 0;    ///< t_imu_ns - t_cam_ns exactly
  double td_s() const { return static_cast<double>(td_ns) * 1e-9; }
};

/// td(0) = td0; drift: td(k) = td(k-1) + bias * dt_k + noise * sqrt(dt_k) * N(0,1), dt_k = t_k - t_{k-1};
/// wander: td(k) = td0 + A·sin(2π·(t_k − t_0)/P).
/// The offset is kept in integer ns so that t_cam + td = t_imu holds exactly in the written files.
/// Throws UsageError if the resulting camera stamps would not be strictly increasing.
std::vector<TimedImage> apply_td_model(const std::vector<int64_t> &t_imu_ns, const TdModelOptions &opt);

} // namespace ovton::sim
