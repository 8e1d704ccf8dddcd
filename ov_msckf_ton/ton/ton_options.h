#pragma once
// Options of the paper's networks (Table I) and of the parts that use them in the filter: each network's training,
// FVON's provider, TPN's driver. They are nested in the estimator's options tree (core/vio_options.h, section `ton`);
// the defaults here are the product's, measured in docs/ton.md; config/paper/estimator_config.yaml restores the
// paper's own choices (no plateau stop, no warm-up cap, no skip connections).
#include <algorithm>

namespace ovton::msckf {
namespace ton {

struct TrainOptions {
  double learning_rate = 1e-3;
  /// Upper bound on Adam steps per training call (per frame, in the filter).
  int max_epochs = 1000;
  /// Stop as soon as the MSE (in normalised units) falls below this; <= 0 disables early stopping.
  double loss_threshold = 0.0;
  /// Plateau stop (beyond Table I, for the per-frame cost): every `plateau_epochs` steps, stop when the loss fell
  /// by less than `plateau_rel` of itself since the previous check. Warm-started from the previous frame, whose
  /// window differs by a few labels, the weights are usually near their optimum after a few dozen steps and the
  /// remaining epochs of the paper's budget buy nothing measurable (docs/ton.md). 0 disables it.
  int plateau_epochs = 0;
  double plateau_rel = 1e-3;
  /// Warm-up, then maintenance (beyond Table I, for the per-frame cost): after `warmup_calls` training calls the cap
  /// per call is `maintenance_epochs` instead of max_epochs. A network learns its mapping over its first calls; later
  /// each call only follows a window that differs by a few labels, which a few hundred warm-started steps do
  /// (docs/ton.md, "Cost"). 0 disables it.
  int warmup_calls = 0;
  int maintenance_epochs = 0;
  /// The options of the `call`-th training call (0-based).
  TrainOptions for_call(int call) const {
    TrainOptions o = *this;
    if (warmup_calls > 0 && call >= warmup_calls)
      o.max_epochs = std::min(max_epochs, maintenance_epochs);
    return o;
  }
};

/// FVON trains once per frame: after its first 100 calls a call is capped at 200 epochs (TrainOptions::warmup_calls).
constexpr int kFvonWarmupCalls = 100, kFvonMaintenanceEpochs = 200;

struct ItsFvonOptions {
  /// Paper Table I: lr 1e-4, up to 1000 epochs or loss < 1e-5; the plateau stop and the warm-up cap (docs/ton.md).
  TrainOptions train{1e-4, 1000, 1e-5, 20, 0.01, kFvonWarmupCalls, kFvonMaintenanceEpochs};
  unsigned seed = 1;
  /// Velocity spread [px/s] below which the window is treated as flat by the normaliser.
  double min_velocity_range = 1.0;
  /// Learn the change V^k − V^{k+1} instead of V^k (a skip connection around the same LSTM): an untrained or
  /// mistrained net then predicts ≈ V^{k+1} (the constant-speed rule) instead of an arbitrary velocity. Not the
  /// paper's output; measured against the truth in docs/ton.md (`ovton velocities`).
  bool residual = true;
};

struct F2fFvonOptions {
  /// Paper Table I: lr 0.01, 1500 epochs; the paper gives no loss threshold, so early stopping is off. Plateau stop and
  /// warm-up cap as ITS's.
  TrainOptions train{0.01, 1500, 0.0, 20, 0.01, kFvonWarmupCalls, kFvonMaintenanceEpochs};
  unsigned seed = 2;
  /// Spreads below which a dimension is treated as flat: position [m], velocity [px/s].
  double min_position_range = 1e-3;
  double min_velocity_range = 1.0;
  /// Feed the 3D position as (X/Z, Y/Z, 1/Z) instead of (X, Y, Z): the same point, in coordinates in which the image
  /// velocity is a low-order polynomial (ω enters through x, y; translation through 1/Z), so that new features —
  /// detected where no tracked feature is, i.e. outside the labels — are less of an extrapolation. Not the paper's
  /// input; measured in docs/ton.md. (min_position_range then applies to these coordinates.)
  bool inverse_depth_input = true;
};

struct TpnOptions {
  /// Paper Table I: lr 1e-4, up to 1000 epochs or loss < 1e-8; the plateau stop as FVON's. TPN trains once per label,
  /// not per frame: no warm-up cap.
  TrainOptions train{1e-4, 1000, 1e-8, 20, 0.01};
  /// Algorithm 1: the label buffer holds the last 30 estimates.
  int buffer_size = 30;
  unsigned seed = 3;
  /// Window spread [s] below which t_d is treated as flat. 10 us shifts a 300 px/s feature by 0.003 px, so a flat
  /// window is not worth resolving more finely, and this keeps a network error from being amplified by ~1/spread.
  double min_range_s = 1e-5;
  /// Learn the step t_d(j+1) − t_d(j) instead of t_d(j+1) (a skip connection around the same LSTM): the net then
  /// only has to represent the drift rate, and an untrained net predicts "no change" instead of an arbitrary value.
  /// Not the paper's output; measured in docs/ton.md.
  bool residual = true;
};

} // namespace ton

struct FvonProviderOptions {
  ton::ItsFvonOptions its;
  ton::F2fFvonOptions f2f;
  /// Training labels per network call: (V^{k+1} -> V^k) pairs for ITS, (point, velocity) pairs for F2F. Bounds the
  /// per-frame cost, which grows linearly with it (times the epochs).
  int max_labels = 40;
  /// F2F needs at least this many labelled features in the frame: 57 weights fitted to fewer points of a smooth
  /// velocity field extrapolate arbitrarily, and a wrong velocity biases t_d.
  int min_f2f_labels = 5;
  /// Algorithm 1: a new feature "tracked over 3 consecutive frames" gets ITS, otherwise F2F.
  int its_min_later = 3;
  /// Sanity check before a prediction enters the update [px/s; 0 = none]: under the constant-speed model the first
  /// observation's velocity equals the next one's, which the track measures. A network extrapolating outside its
  /// labels (F2F on a handful of points, ITS on an unusual track) can be off by hundreds of px/s, and every such
  /// velocity becomes a wrong t_d regressor; a missing velocity only costs the feature its t_d column. 80 px/s is ~3σ
  /// of a 1 px backward difference at 20 Hz.
  double gate_px_s = 80.0;
};

struct TpnDriverOptions {
  ton::TpnOptions tpn;
  /// Below this many labels the rate is 0: a window of a few filter estimates is mostly the filter's convergence
  /// transient, not the offset's own motion.
  int min_labels = 5;
  /// |J_td| bound [s/s]. Real clock drifts are ppm (1e-6 s/s) and the paper's simulated drift 1e-4 s/s; 1e-3 s/s
  /// still allows 10x that, but keeps a badly trained network from moving t_d by more than 0.05 ms per 20 Hz frame,
  /// which the update would then have to undo.
  double td_rate_max = 0.001;
};

} // namespace ovton::msckf
