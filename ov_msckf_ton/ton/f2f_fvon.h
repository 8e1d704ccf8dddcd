#pragma once
// F2F-FVON (paper Sec. IV-B.2, eq. 8-10): learns the image-velocity field of one frame as a function of a feature's
// 3D position in that camera frame, from the features whose velocity the constant-speed model gives, and predicts
// it for the features that were just detected.
#include "ov_msckf_ton/ton/adam.h"
#include "ov_msckf_ton/ton/min_max_normalizer.h"
#include "ov_msckf_ton/ton/mlp.h"
#include "ov_msckf_ton/ton/trainer.h"

#include <Eigen/Core>
#include <vector>

namespace ovton::msckf {
namespace ton {

class F2fFvon {
public:
  explicit F2fFvon(const F2fFvonOptions &options = F2fFvonOptions());

  /// Re-initialises the weights from the seed and forgets the optimiser state and labels.
  void reset();

  /// Drops the current frame's labels; the weights are kept (warm start).
  void clear_labels();
  /// One well-tracked feature of frame k: its 3D position in camera frame k [m] and its velocity (eq. 2) [px/s].
  void add_label(const Eigen::Vector3d &p_in_cam, const Eigen::Vector2d &velocity);
  int num_labels() const { return static_cast<int>(positions_.size()); }

  /// Fits both normalisers on the frame's labels and continues training from the previous weights. Without labels
  /// it leaves the network untouched and returns an empty report.
  TrainReport train();
  bool trained() const { return trained_; }

  /// Velocity [px/s] of a feature at `p_in_cam` in the frame last trained on. Throws if never trained.
  Eigen::Vector2d predict(const Eigen::Vector3d &p_in_cam) const;

  const F2fMlp &network() const { return net_; }
  const TrainReport &last_report() const { return last_report_; }
  const F2fFvonOptions &options() const { return options_; }

private:
  Eigen::Vector3d input(const Eigen::Vector3d &p_in_cam) const;
  F2fFvonOptions options_;
  F2fMlp net_;
  Adam<F2fMlp::kNumParams> adam_;
  MinMaxNormalizer<3> pos_norm_;
  MinMaxNormalizer<2> vel_norm_;
  std::vector<Eigen::Vector3d> positions_;
  std::vector<Eigen::Vector2d> velocities_;
  F2fMlp::Data data_;
  TrainReport last_report_;
  bool trained_ = false;
  int calls_ = 0; // training calls so far (TrainOptions::for_call)
};

} // namespace ton
} // namespace ovton::msckf
