#pragma once
// How the time offset t_d moves between images (t_imu = t_cam + t_d): one interface, one implementation per model,
// each owning its prediction, its process noise and its learning. A new model is one new file and one line in
// make_td_model(). How t_d is *observed* (clone time, image plane, not at all) is the mode's business (td_mode.h).
//
// The VioManager asks the model where t_d will be at the next image (the replay feeds IMU readings up to
// t_cam + that), propagates the IMU there, lets the model move the t_d mean and grow its covariance over the same
// IMU-clock interval, and after each update and each image tells the model what happened.
#include "ov_msckf_ton/core/vio_options.h"
#include "ov_msckf_ton/state/state.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace ovton::msckf {

/// What a model did so far (run summaries, tests).
struct TdModelStats {
  long rate_clamped = 0;   ///< propagations whose rate hit time_offset.rate_max (tpn)
  long learning_steps = 0; ///< TPN trainings
  /// TPN's start (1-based image counts; -1: not yet): the first image whose t̂_d became a label (its σ below
  /// ton.tpn_start_sigma_s), the image after which TPN first predicted (until then t_d's rate is 0: a random walk),
  /// and how often the labels started over because σ rose above that bound again.
  long tpn_first_label_image = -1, tpn_first_prediction_image = -1, tpn_label_restarts = 0;
  long propagations = 0;      ///< propagations over a positive interval (tpn: the denominator of rate_clamped)
  double process_sigma = 0.0; ///< current process noise [s/sqrt(s)] on t_d (adaptive models change it)
  /// The model check (td_model_check.h): IMU time at which t_d went to the drift state (-1: never), the smaller of
  /// the two stretches' sums in sigmas, and what the corrections moved t_d by over both [s].
  int64_t switched_ns = -1;
  double check_z = 0.0, check_moved_s = 0.0;
};

class TdModel {
public:
  virtual ~TdModel() = default;
  virtual TdProcess kind() const = 0;

  /// Called once when the filter initialises, after the IMU block and t_d have their priors: adds the model's own
  /// variables (the drift state's rate) with their priors.
  virtual void initialize(State &) {}

  /// t_d [s] the propagation to the image stamped t_cam_ns will end at. `last_image_ns` is the camera stamp of the
  /// previous image (-1 before the first).
  virtual double td_at_image(const State &s, int64_t t_cam_ns, int64_t last_image_ns) const = 0;

  /// Moves the t_d mean to td_end (the value td_at_image returned) and grows the covariance of the model's block
  /// (t_d, and the rate for the drift state) over dt_s seconds of IMU clock. The IMU block has already been
  /// propagated over the same interval.
  virtual void propagate(State &s, double td_end, double dt_s) = 0;

  /// After each EKF update: t_d's mean and variance before and after (adaptive noise uses the corrections).
  virtual void after_update(double /*td_prior*/, double /*var_prior*/, double /*td_post*/, double /*var_post*/) {}

  /// After each processed image (update done): learning from the filter's estimate (TPN).
  virtual void after_image(const State &, int64_t /*t_cam_ns*/) {}

  const TdModelStats &stats() const { return stats_; }

protected:
  TdModelStats stats_;
};

/// The model the options ask for (time_offset.mode and .process). `truth` gives the true offset at a camera stamp;
/// it is needed (and only used) by mode oracle.
std::unique_ptr<TdModel> make_td_model(const VioOptions &opt, std::function<double(int64_t)> truth = {});

/// Adds process noise to the t_d variance and, for the drift state, propagates its rate: shared by the models.
/// P_td += q_td² dt; with a rate index, Φ = [[1, dt], [0, 1]] on (t_d, ṫ_d) and the continuous white-noise
/// acceleration model Q = q_r² [[dt³/3, dt²/2], [dt²/2, dt]] on top.
void propagate_td_covariance(State &s, double q_td, double q_rate, double dt_s);

/// The same for any offset at covariance index `d` with its rate at `r` (−1: none): t_d, or a further camera's Δ
/// (time_offset.per_camera).
void propagate_offset_covariance(State &s, int d, int r, double q_td, double q_rate, double dt_s);

} // namespace ovton::msckf
