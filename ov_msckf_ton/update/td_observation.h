#pragma once
// How the camera-IMU time offset t_d enters a feature measurement (t_imu = t_cam + t_d), and where the image-plane
// velocity of an observation comes from.
#include "ov_core/track/feature_database.h"

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

namespace ovton::msckf {

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

/// How an observation's velocity depends on the measured points of its own track, to first order:
/// δvel_xy = Σ W_j·δxy_j over the track's observations j (exact for the differences below, which are linear in the
/// points; a network's prediction through its input Jacobian). The update needs it because such a velocity shares
/// pixel noise with the residual rows it multiplies, which biases t̂_d (errors in variables;
/// UpdaterMSCKFOptions::td_velocity_debias). Empty: the velocity does not depend on the track's points, as far as
/// is modelled.
struct VelocityStencil {
  std::vector<std::pair<size_t, Eigen::Matrix2d>> terms;

  void clear() { terms.clear(); }
  void add(size_t obs_index, const Eigen::Matrix2d &weight) {
    for (auto &[i, w] : terms)
      if (i == obs_index) {
        w += weight;
        return;
      }
    terms.emplace_back(obs_index, weight);
  }
  void add(size_t obs_index, double weight) { add(obs_index, weight * Eigen::Matrix2d::Identity()); }
  /// Adds scale · other (the stencil of a velocity that is a linear map of another velocity).
  void add(const VelocityStencil &other, const Eigen::Matrix2d &scale) {
    for (const auto &[i, w] : other.terms)
      add(i, scale * w);
  }
};

/// Supplies the image-plane velocity of one observation in undistorted normalised coordinates per second.
/// The default is the constant-speed model of the front end (paper eq. 2); FVON overrides it for observations
/// without a previous one.
class VelocityProvider {
public:
  virtual ~VelocityProvider() = default;
  /// Returns false when the observation has no usable velocity: its measurement row then carries no t_d entry
  /// and does not constrain t_d. `source` is one of VelocitySource.
  virtual bool velocity(const ovton::core::Feature &feature, size_t obs_index, Eigen::Vector2d &vel_xy,
                        int &source) const {
    const ovton::core::FeatureObservation &o = feature.obs[obs_index];
    if (!o.vel_valid) {
      source = kVelocityNone;
      return false;
    }
    vel_xy = o.vel_xy;
    source = kVelocityTracked;
    return true;
  }
  /// What velocity() returns for this observation as a combination of the track's points (eq. 2 here). Must follow
  /// velocity(): an override of one overrides the other.
  virtual void stencil(const ovton::core::Feature &feature, size_t obs_index, VelocityStencil &out) const {
    out.clear();
    const auto &obs = feature.obs;
    if (!obs[obs_index].vel_valid)
      return;
    // (xy_k − xy_{k−1}) / dt. When the previous observation has already been used and removed from the track (it
    // is then in no residual either), its interval is not kept: assume the next one's.
    const size_t j = obs_index > 0 ? obs_index - 1 : obs_index + 1;
    if (j >= obs.size())
      return;
    const double dt = 1e-9 * std::abs(static_cast<double>(obs[obs_index].t_cam_ns - obs[j].t_cam_ns));
    out.add(obs_index, 1.0 / dt);
    if (obs_index > 0)
      out.add(obs_index - 1, -1.0 / dt);
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
  bool velocity(const ovton::core::Feature &feature, size_t obs_index, Eigen::Vector2d &vel_xy,
                int &source) const override {
    size_t used = 0;
    return taken_from(feature, obs_index, vel_xy, source, used);
  }
  void stencil(const ovton::core::Feature &feature, size_t obs_index, VelocityStencil &out) const override {
    Eigen::Vector2d v;
    int src = kVelocityNone;
    size_t used = 0;
    if (taken_from(feature, obs_index, v, src, used))
      base_.stencil(feature, used, out);
    else
      out.clear();
  }

private:
  /// The base's velocity of this observation, else of the next one; `used` says whose.
  bool taken_from(const ovton::core::Feature &feature, size_t obs_index, Eigen::Vector2d &vel_xy, int &source,
                  size_t &used) const {
    for (used = obs_index; used <= obs_index + 1 && used < feature.obs.size(); ++used)
      if (base_.velocity(feature, used, vel_xy, source))
        return true;
    source = kVelocityNone;
    return false;
  }

  const VelocityProvider &base_;
};

/// Central-difference velocity (x_{k+1} − x_{k−1}) / (t_{k+1} − t_{k−1}) for observations with a neighbour on each
/// side, the backward difference of eq. 2 for a track's newest observation. Why: eq. 2's V_k contains the pixel noise
/// of observation k itself, which is also in that row's residual; the correlated regressor biases t̂_d (errors in
/// variables). The central difference leaves observation k out and is centred on t_k instead of half a frame late.
/// Not the paper's SIR: an option (`sir_velocity: central`) to measure what eq. 2 costs.
class CentralVelocityProvider : public VelocityProvider {
public:
  bool velocity(const ovton::core::Feature &feature, size_t obs_index, Eigen::Vector2d &vel_xy,
                int &source) const override {
    const auto &obs = feature.obs;
    if (!obs[obs_index].vel_valid) {
      source = kVelocityNone;
      return false;
    }
    double dt0 = 0.0, dt1 = 0.0;
    if (central(feature, obs_index, dt0, dt1))
      vel_xy = (obs[obs_index].vel_xy * dt0 + obs[obs_index + 1].vel_xy * dt1) / (dt0 + dt1);
    else
      vel_xy = obs[obs_index].vel_xy;
    source = kVelocityTracked;
    return true;
  }
  void stencil(const ovton::core::Feature &feature, size_t obs_index, VelocityStencil &out) const override {
    double dt0 = 0.0, dt1 = 0.0;
    if (!central(feature, obs_index, dt0, dt1)) {
      VelocityProvider::stencil(feature, obs_index, out);
      return;
    }
    VelocityStencil back, next;
    VelocityProvider::stencil(feature, obs_index, back);
    VelocityProvider::stencil(feature, obs_index + 1, next);
    out.clear();
    out.add(back, dt0 / (dt0 + dt1) * Eigen::Matrix2d::Identity());
    out.add(next, dt1 / (dt0 + dt1) * Eigen::Matrix2d::Identity());
  }

private:
  /// Whether the observation has a valid neighbour on each side, and the two intervals.
  static bool central(const ovton::core::Feature &feature, size_t obs_index, double &dt0, double &dt1) {
    const auto &obs = feature.obs;
    if (!(obs[obs_index].vel_valid && obs_index + 1 < obs.size() && obs[obs_index + 1].vel_valid))
      return false;
    dt1 = 1e-9 * static_cast<double>(obs[obs_index + 1].t_cam_ns - obs[obs_index].t_cam_ns);
    // The previous observation may belong to the part of the track already used and removed (its velocity was
    // kept): then assume the frame interval was the same.
    dt0 = obs_index > 0 ? 1e-9 * static_cast<double>(obs[obs_index].t_cam_ns - obs[obs_index - 1].t_cam_ns) : dt1;
    return true;
  }
};

} // namespace ovton::msckf
