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
