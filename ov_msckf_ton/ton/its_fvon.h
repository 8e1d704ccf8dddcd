#pragma once
// ITS-FVON (paper Sec. IV-B.1, eq. 6-7): predicts the image velocity V^k of a feature first seen in frame k from
// the velocities it shows in later frames, V^{k+1}, V^{k+2}, ... (an inverse time series).
#include "ov_msckf_ton/ton/adam.h"
#include "ov_msckf_ton/ton/lstm.h"
#include "ov_msckf_ton/ton/min_max_normalizer.h"
#include "ov_msckf_ton/ton/trainer.h"

#include <Eigen/Core>
#include <random>
#include <vector>

namespace ovton::msckf {
namespace ton {

class ItsFvon {
public:
  explicit ItsFvon(const ItsFvonOptions &options = ItsFvonOptions());

  /// Re-initialises the weights from the seed and forgets the optimiser state and labels.
  void reset();

  /// Drops the current window's labels; the weights are kept (warm start).
  void clear_tracks();
  /// Adds the velocities of one well-tracked feature in time order, V^j, V^{j+1}, ..., V^{j+m-1} (m >= 2; shorter
  /// tracks carry no (V^{k+1} -> V^k) pair and are ignored). Each becomes one training sequence, fed in reverse time
  /// with targets one step earlier, so the hidden state carries the later frames' trend as the paper's Fig. 3 does.
  void add_track(const Eigen::Vector2d *velocities, int count);
  void add_track(const std::vector<Eigen::Vector2d> &velocities) {
    add_track(velocities.data(), static_cast<int>(velocities.size()));
  }
  int num_tracks() const { return static_cast<int>(starts_.size()); }

  /// Fits the normaliser on every velocity of the window and continues training from the previous weights.
  /// Without tracks it leaves the network untouched and returns an empty report.
  TrainReport train();
  bool trained() const { return trained_; }

  /// V^k from V^{k+1}, ..., V^{k+n} (time order, n >= 1), using the last fitted normaliser. Throws if never trained.
  Eigen::Vector2d predict(const Eigen::Vector2d *future, int count) const;
  Eigen::Vector2d predict(const std::vector<Eigen::Vector2d> &future) const {
    return predict(future.data(), static_cast<int>(future.size()));
  }

  const ItsLstm &network() const { return net_; }
  const TrainReport &last_report() const { return last_report_; }
  const ItsFvonOptions &options() const { return options_; }
  /// The fitted normaliser's spread per dimension [px/s] (the scale a derivative step must be small against).
  const Eigen::Vector2d &input_scale() const { return norm_.scale(); }

private:
  ItsFvonOptions options_;
  ItsLstm net_;
  Adam<ItsLstm::kNumParams> adam_;
  MinMaxNormalizer<2> norm_;
  std::vector<Eigen::Vector2d> raw_; // all tracks back to back, time order
  std::vector<int> starts_;
  ItsLstm::Data data_;
  TrainReport last_report_;
  bool trained_ = false;
  int calls_ = 0; // training calls so far (TrainOptions::for_call)
};

} // namespace ton
} // namespace ovton::msckf
