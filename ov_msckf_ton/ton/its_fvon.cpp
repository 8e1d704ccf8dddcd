#include "ov_msckf_ton/ton/its_fvon.h"

namespace ovton::msckf {
namespace ton {

ItsFvon::ItsFvon(const ItsFvonOptions &options)
    : options_(options), adam_(options.train.learning_rate),
      norm_(Eigen::Vector2d::Constant(options.min_velocity_range)) {
  reset();
}

void ItsFvon::reset() {
  std::mt19937 rng(options_.seed);
  net_.init(rng);
  adam_.reset();
  clear_tracks();
  trained_ = false;
  last_report_ = TrainReport();
}

void ItsFvon::clear_tracks() {
  raw_.clear();
  starts_.clear();
}

void ItsFvon::add_track(const Eigen::Vector2d *velocities, int count) {
  if (count < 2)
    return;
  OVTON_TON_CHECK(velocities != nullptr, "ItsFvon::add_track: null velocities");
  for (int k = 0; k < count; ++k)
    OVTON_TON_CHECK(velocities[k].allFinite(), "ItsFvon::add_track: non-finite velocity");
  starts_.push_back(static_cast<int>(raw_.size()));
  raw_.insert(raw_.end(), velocities, velocities + count);
}

TrainReport ItsFvon::train() {
  if (starts_.empty())
    return last_report_ = TrainReport();
  norm_.reset();
  for (const auto &v : raw_)
    norm_.add(v);
  norm_.finish();

  data_.clear();
  for (size_t s = 0; s < starts_.size(); ++s) {
    const int b = starts_[s];
    const int e = s + 1 < starts_.size() ? starts_[s + 1] : static_cast<int>(raw_.size());
    data_.begin_sequence();
    // Reverse time: input V^{j+1}, target V^j, walking back to the track's first velocity.
    for (int k = e - 1; k > b; --k) {
      const Eigen::Vector2d in = norm_.normalize(raw_[k]);
      data_.push(in, options_.residual ? Eigen::Vector2d(norm_.normalize(raw_[k - 1]) - in)
                                       : Eigen::Vector2d(norm_.normalize(raw_[k - 1])));
    }
  }
  last_report_ = train_network(net_, adam_, data_, options_.train.for_call(calls_++));
  trained_ = true;
  return last_report_;
}

Eigen::Vector2d ItsFvon::predict(const Eigen::Vector2d *future, int count) const {
  OVTON_TON_CHECK(trained_, "ItsFvon::predict before train");
  OVTON_TON_CHECK(future != nullptr && count >= 1, "ItsFvon::predict needs at least V^{k+1}");
  ItsLstm::State state;
  Eigen::Vector2d y = Eigen::Vector2d::Zero();
  for (int k = count - 1; k >= 0; --k) {
    OVTON_TON_CHECK(future[k].allFinite(), "ItsFvon::predict: non-finite velocity");
    y = net_.step(norm_.normalize(future[k]), state);
  }
  if (options_.residual)
    y += norm_.normalize(future[0]);
  return norm_.denormalize(y);
}

} // namespace ton
} // namespace ovton::msckf
