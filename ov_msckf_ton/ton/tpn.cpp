#include "ov_msckf_ton/ton/tpn.h"

#include <cmath>
#include <random>

namespace ovton::msckf {
namespace ton {

Tpn::Tpn(const TpnOptions &options)
    : options_(options), adam_(options.train.learning_rate),
      norm_(Eigen::Matrix<double, 1, 1>::Constant(options.min_range_s)) {
  OVTON_TON_CHECK(options.buffer_size >= 2, "Tpn: buffer_size must be at least 2");
  buffer_.reserve(options.buffer_size);
  data_.reserve(options.buffer_size, 1);
  reset();
}

void Tpn::reset() {
  std::mt19937 rng(options_.seed);
  net_.init(rng);
  adam_.reset();
  buffer_.clear();
  trained_ = false;
  last_report_ = TrainReport();
}

void Tpn::push_estimate(double td_s) {
  OVTON_TON_CHECK(std::isfinite(td_s), "Tpn::push_estimate: non-finite time offset");
  if (static_cast<int>(buffer_.size()) >= options_.buffer_size)
    buffer_.erase(buffer_.begin()); // 30 doubles: cheaper than a ring buffer's bookkeeping, and no allocation
  buffer_.push_back(td_s);
}

void Tpn::fit_normalizer() {
  norm_.reset();
  for (double td : buffer_)
    norm_.add(Eigen::Matrix<double, 1, 1>(td));
  norm_.finish();
}

TrainReport Tpn::train() {
  if (buffer_.size() < 2)
    return last_report_ = TrainReport();
  fit_normalizer();
  data_.clear();
  data_.begin_sequence();
  for (size_t j = 0; j + 1 < buffer_.size(); ++j) {
    const Eigen::Matrix<double, 1, 1> in = norm_.normalize(Eigen::Matrix<double, 1, 1>(buffer_[j]));
    const Eigen::Matrix<double, 1, 1> next = norm_.normalize(Eigen::Matrix<double, 1, 1>(buffer_[j + 1]));
    data_.push(in, options_.residual ? Eigen::Matrix<double, 1, 1>(next - in) : next);
  }
  last_report_ = train_network(net_, adam_, data_, options_.train);
  trained_ = true;
  return last_report_;
}

double Tpn::predict() const {
  OVTON_TON_CHECK(trained_, "Tpn::predict before train");
  OVTON_TON_CHECK(!buffer_.empty(), "Tpn::predict with an empty label buffer");
  // The normaliser was fitted in train(); if estimates were pushed since, inputs may fall slightly outside [0,1],
  // which the network tolerates better than a window it was not trained on.
  TpnLstm::State state;
  Eigen::Matrix<double, 1, 1> y = Eigen::Matrix<double, 1, 1>::Zero();
  for (double td : buffer_)
    y = net_.step(norm_.normalize(Eigen::Matrix<double, 1, 1>(td)), state);
  if (options_.residual)
    y += norm_.normalize(Eigen::Matrix<double, 1, 1>(buffer_.back()));
  return norm_.denormalize(y)[0];
}

} // namespace ton
} // namespace ovton::msckf
