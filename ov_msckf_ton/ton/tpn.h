#pragma once
// TPN (paper Sec. IV-C, eq. 11-12, Algorithm 1 stages 3-4): learns how the time offset evolves from the filter's
// own recent estimates and predicts the next one. The filter turns the prediction into a drift rate,
// J_td = (t_d^TPN(K) - t_d(K-1)) / dt (eq. 14), for its propagation.
#include "ov_msckf_ton/ton/adam.h"
#include "ov_msckf_ton/ton/lstm.h"
#include "ov_msckf_ton/ton/min_max_normalizer.h"
#include "ov_msckf_ton/ton/trainer.h"

#include <vector>

namespace ovton::msckf {
namespace ton {

struct TpnOptions {
  /// Paper Table I: lr 1e-4, up to 1000 epochs or loss < 1e-8.
  TrainOptions train{1e-4, 1000, 1e-8};
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

class Tpn {
public:
  explicit Tpn(const TpnOptions &options = TpnOptions());

  /// Re-initialises the weights from the seed and forgets the optimiser state and the label buffer.
  void reset();

  /// Stage 3: appends the filter's estimate t_d(K-1) [s], dropping the oldest once the buffer is full.
  void push_estimate(double td_s);
  int num_labels() const { return static_cast<int>(buffer_.size()); }
  /// Empties the label buffer, keeping the weights and the optimiser state.
  void clear_labels() { buffer_.clear(); }
  const std::vector<double> &labels() const { return buffer_; }

  /// Stage 4: trains on the buffer as one sequence, input t_d(j) -> target t_d(j+1), continuing from the previous
  /// weights. Needs at least two labels; otherwise returns an empty report and leaves the network untouched.
  TrainReport train();
  bool trained() const { return trained_; }

  /// t_d^TPN(K) [s]: runs the whole normalised buffer through the LSTM so the hidden state carries the window's
  /// trend, and reads the output after the last input t_d(K-1). Throws if never trained or the buffer is empty.
  double predict() const;

  const TpnLstm &network() const { return net_; }
  const TrainReport &last_report() const { return last_report_; }
  const TpnOptions &options() const { return options_; }

private:
  void fit_normalizer();

  TpnOptions options_;
  TpnLstm net_;
  Adam<TpnLstm::kNumParams> adam_;
  MinMaxNormalizer<1> norm_;
  std::vector<double> buffer_; // oldest first
  TpnLstm::Data data_;
  TrainReport last_report_;
  bool trained_ = false;
};

} // namespace ton
} // namespace ovton::msckf
