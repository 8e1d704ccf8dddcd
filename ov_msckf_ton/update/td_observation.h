#pragma once
// How the camera-IMU time offset t_d enters a feature measurement (t_imu = t_cam + t_d), and where the image-plane
// velocity of an observation comes from.
#include "ov_core/track/feature_database.h"

#include <Eigen/Core>
#include <cstddef>

namespace ov_msckf_ton {

/// The role t_d plays in the MSCKF measurement of one update.
enum class TdObservation {
  /// t_d does not appear (mode `off`, `oracle`): z = h(clone).
  None,
  /// Mode `sr`: z = h(clone) as well; the clone itself depends on t_d through its cloning Jacobian, which the
  /// covariance already carries, so the measurement adds nothing.
  StateRelevant,
  /// Modes `sir`, `fvon`, `tpn`, `ton` (TON-VIO paper eq. 1): the image was taken at IMU time t_cam + t_d but the
  /// clone sits at t_cam + td_ref, so the feature has moved by V·(t_d − td_ref) on the image plane:
  ///   z = h(clone) + V·(t_d − td_ref) + n.
  /// Equivalently the shifted measurement z(t_d) = z − V·(t_d − td_ref) is compared with h(clone) (paper eq. 1 with
  /// ∂z(t_d)/∂t_d = −V).
  ImagePlane,
};

/// Where an observation's image-plane velocity came from; the residual log and the update statistics count by it.
enum VelocitySource : int {
  kVelocityNone = 0,
  kVelocityTracked = 1, ///< constant-speed difference with the previous observation (paper eq. 2)
  kVelocityItsFvon = 2, ///< predicted by ITS-FVON from later velocities of the same track
  kVelocityF2fFvon = 3, ///< predicted by F2F-FVON from the feature's 3D position
};
constexpr int kNumVelocitySources = 4;

/// Supplies the image-plane velocity of one observation in undistorted normalised coordinates per second.
/// The default is the constant-speed model of the front end (paper eq. 2); FVON overrides it for observations
/// without a previous one.
class VelocityProvider {
public:
  virtual ~VelocityProvider() = default;
  /// Returns false when the observation has no usable velocity: its measurement row then carries no t_d entry
  /// and does not constrain t_d. `source` is one of VelocitySource.
  virtual bool velocity(const ov_core::Feature &feature, size_t obs_index, Eigen::Vector2d &vel_xy, int &source) const {
    const ov_core::FeatureObservation &o = feature.obs[obs_index];
    if (!o.vel_valid) {
      source = kVelocityNone;
      return false;
    }
    vel_xy = o.vel_xy;
    source = kVelocityTracked;
    return true;
  }
};

/// A track's first observation has no previous one, so eq. 2 gives it no velocity, and the all-or-nothing rule of
/// the update then keeps the whole feature from constraining t_d until that observation has left the window. This
/// gives it the velocity measured at the next observation (constant-speed model, V^0 ≈ V^1), the "copy next" rule
/// ITS-FVON is compared with. Not the paper's SIR: an option (`sir_first_velocity: next`) for sir and tpn, where no
/// FVON predicts first velocities.
class NextForFirstVelocityProvider : public VelocityProvider {
public:
  explicit NextForFirstVelocityProvider(const VelocityProvider &base) : base_(base) {}
  bool velocity(const ov_core::Feature &feature, size_t obs_index, Eigen::Vector2d &vel_xy,
                int &source) const override {
    if (base_.velocity(feature, obs_index, vel_xy, source))
      return true;
    if (obs_index + 1 < feature.obs.size() && base_.velocity(feature, obs_index + 1, vel_xy, source))
      return true;
    source = kVelocityNone;
    return false;
  }

private:
  const VelocityProvider &base_;
};

/// Central-difference velocity (x_{k+1} − x_{k−1}) / (t_{k+1} − t_{k−1}) for observations with a neighbour on each
/// side, the backward difference of eq. 2 for a track's newest observation. Why: eq. 2's V_k contains the pixel noise
/// of observation k itself, which is also in that row's residual; the correlated regressor biases t̂_d (errors in
/// variables). The central difference leaves observation k out and is centred on t_k instead of half a frame late.
/// Not the paper's SIR: an option (`sir_velocity: central`) to measure what eq. 2 costs.
class CentralVelocityProvider : public VelocityProvider {
public:
  bool velocity(const ov_core::Feature &feature, size_t obs_index, Eigen::Vector2d &vel_xy,
                int &source) const override {
    const auto &obs = feature.obs;
    if (!obs[obs_index].vel_valid) {
      source = kVelocityNone;
      return false;
    }
    if (obs_index + 1 < obs.size() && obs[obs_index + 1].vel_valid) {
      const double dt1 = 1e-9 * static_cast<double>(obs[obs_index + 1].t_cam_ns - obs[obs_index].t_cam_ns);
      // The previous observation may belong to the part of the track already used and removed (its velocity was
      // kept): then assume the frame interval was the same.
      const double dt0 =
          obs_index > 0 ? 1e-9 * static_cast<double>(obs[obs_index].t_cam_ns - obs[obs_index - 1].t_cam_ns) : dt1;
      vel_xy = (obs[obs_index].vel_xy * dt0 + obs[obs_index + 1].vel_xy * dt1) / (dt0 + dt1);
    } else {
      vel_xy = obs[obs_index].vel_xy;
    }
    source = kVelocityTracked;
    return true;
  }
};

} // namespace ov_msckf_ton
