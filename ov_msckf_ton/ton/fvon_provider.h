#pragma once
// FVON inside the MSCKF update (paper Algorithm 1, stages 1-2): the velocity of an observation that has no previous
// observation (a track's first, i.e. a new detection) is predicted, so that the feature can constrain t_d in the
// image-plane model z = h(clone) + V·(t_d − td_ref). Tracked velocities (paper eq. 2) are passed through unchanged.
#include "ov_core/cam/camera_calib.h"
#include "ov_core/track/feature_database.h"
#include "ov_msckf_ton/state/state.h"
#include "ov_msckf_ton/ton/f2f_fvon.h"
#include "ov_msckf_ton/ton/its_fvon.h"
#include "ov_msckf_ton/update/td_observation.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

namespace ovton::msckf {

class UpdaterMSCKF;

/// What the networks said about one first observation (for the velocity log). Velocities in normalised units/s.
struct FvonCandidates {
  bool has_its = false, has_f2f = false;
  Eigen::Vector2d its = Eigen::Vector2d::Zero(), f2f = Eigen::Vector2d::Zero();
  int chosen = 0;     ///< VelocitySource of the prediction the filter was offered (0: none)
  bool gated = false; ///< that prediction failed the sanity check
};

/// Counts of what prepare() did since construction (diagnostics; the updater counts what was used).
struct FvonStats {
  long its_trainings = 0, f2f_trainings = 0;
  long its_predictions = 0, f2f_predictions = 0;
  long no_prediction = 0; ///< first observations left without a velocity (too few labels, untriangulable point)
  long gated = 0;         ///< predictions dropped by the sanity check (gate_px_s)
};

/// Not thread-safe; one per filter. Call prepare() before each update with the features of that update, then pass
/// the provider to UpdaterMSCKF::update().
class FvonVelocityProvider : public VelocityProvider {
public:
  /// `stencils`: give each ITS prediction its stencil (the network's input Jacobian, by central differences: 2
  /// predictions per input velocity), for the update's errors-in-variables correction (time_offset.velocity_debias).
  FvonVelocityProvider(const ovton::core::CameraCalib &calib, const FvonProviderOptions &options = {},
                       bool stencils = false);

  /// Trains the networks on the update's well-tracked features (warm start) and predicts the velocity of every
  /// first observation of `features` that has none. Points are triangulated with `updater` from the clone
  /// estimates in `state`. Predictions of the previous call are forgotten.
  void prepare(const State &state, const std::vector<const ovton::core::Feature *> &features,
               const UpdaterMSCKF &updater);

  /// Tracked observations get the velocity of `tracked` (eq. 2's backward difference by default, or the central
  /// difference of time_offset.sir_velocity); first observations FVON's prediction, when it made one.
  bool velocity(const ovton::core::Feature &feature, size_t obs_index, Eigen::Vector2d &vel_xy,
                int &source) const override;
  /// Tracked observations: `tracked`'s; ITS predictions through the later velocities they came from (with
  /// `stencils`); F2F's dependence on the points (through its triangulated input) is left out.
  void stencil(const ovton::core::Feature &feature, size_t obs_index, VelocityStencil &out) const override;
  /// The provider for tracked observations (must outlive this one); default: eq. 2.
  void set_tracked(const VelocityProvider *tracked) { tracked_for_update_ = tracked ? tracked : &tracked_; }

  const FvonStats &stats() const { return stats_; }
  /// For evaluation (`ovton run --velocity-log`): also predict every first observation with the network the rule
  /// did not pick (ITS where F2F was chosen, and the reverse), on a copy of F2F so the filter's own predictions and
  /// hence its trajectory are unchanged. Costs one more F2F training per frame.
  void set_evaluate_both(bool on) { evaluate_both_ = on; }
  /// Per feature id, the candidates of the last prepare() (first observations only).
  const std::unordered_map<size_t, FvonCandidates> &candidates() const { return candidates_; }
  const ton::ItsFvon &its() const { return its_; }
  const ton::F2fFvon &f2f() const { return f2f_; }

private:
  struct Prediction {
    int64_t t_cam_ns = 0;
    Eigen::Vector2d vel_xy = Eigen::Vector2d::Zero();
    int source = kVelocityNone;
    VelocityStencil stencil; ///< ITS with `stencils`: through the later velocities it was predicted from
  };

  /// Stores the prediction unless the sanity check rejects it; returns whether it was kept.
  bool keep_prediction(const ovton::core::Feature &f, const Prediction &p);
  /// ITS-FVON's prediction for a first observation from the track's later velocities (ITS must be trained).
  /// With `stencil`, also how the prediction depends on the track's points (through its input velocities).
  Eigen::Vector2d predict_its(const ovton::core::Feature &f, VelocityStencil *stencil = nullptr);
  /// The stencil of the prediction predict_its just made from the track's n later velocities (in its_seq_).
  void its_stencil(const ovton::core::Feature &f, int n, VelocityStencil &stencil);
  /// The prediction kept for this (first) observation by the last prepare(), or nullptr.
  const Prediction *prediction_for(const ovton::core::Feature &feature, size_t obs_index) const;
  /// F2F-FVON over the frames of `need` (first observations): one training of `net` per frame on the other features'
  /// 3D points and tracked velocities, then `out(feature, velocity)` for each point it can predict. Features of a
  /// frame without enough labels, or untriangulable, are passed to `none`.
  void f2f_pass(const State &state, const std::vector<const ovton::core::Feature *> &features,
                const std::vector<const ovton::core::Feature *> &need, ton::F2fFvon &net,
                const std::function<void(const ovton::core::Feature &, const Eigen::Vector2d &, int64_t)> &out,
                const std::function<void(const ovton::core::Feature &)> &none);

  FvonProviderOptions opt_;
  bool stencils_ = false, evaluate_both_ = false;
  Eigen::Matrix3d R_BC_;
  Eigen::Vector3d p_BC_;
  /// The networks' normalisers have spreads in px/s; the updater works in normalised coordinates per second, so
  /// velocities are scaled by the mean focal length on the way in and back on the way out.
  double focal_;
  ton::ItsFvon its_;
  ton::F2fFvon f2f_;
  VelocityProvider tracked_; ///< constant-speed velocities only, for triangulating before predictions exist
  const VelocityProvider *tracked_for_update_ = &tracked_;
  std::unordered_map<size_t, Prediction> predictions_; ///< by feature id, for its first observation
  std::unordered_map<size_t, FvonCandidates> candidates_;
  /// Triangulated points of the update's features (F2F's inputs), filled once per prepare().
  std::unordered_map<size_t, Eigen::Vector3d> p_W_;
  const UpdaterMSCKF *updater_ = nullptr;
  std::vector<Eigen::Vector2d> its_seq_; ///< scratch
  FvonStats stats_;
};

} // namespace ovton::msckf
