#include "ov_msckf_ton/ton/f2f_fvon.h"

#include <random>

namespace ovton::msckf {
namespace ton {

F2fFvon::F2fFvon(const F2fFvonOptions &options)
    : options_(options), adam_(options.train.learning_rate),
      pos_norm_(Eigen::Vector3d::Constant(options.min_position_range)),
      vel_norm_(Eigen::Vector2d::Constant(options.min_velocity_range)) {
  reset();
}

void F2fFvon::reset() {
  std::mt19937 rng(options_.seed);
  net_.init(rng);
  adam_.reset();
  clear_labels();
  trained_ = false;
  last_report_ = TrainReport();
}

void F2fFvon::clear_labels() {
  positions_.clear();
  velocities_.clear();
}

Eigen::Vector3d F2fFvon::input(const Eigen::Vector3d &p) const {
  if (!options_.inverse_depth_input)
    return p;
  return Eigen::Vector3d(p.x() / p.z(), p.y() / p.z(), 1.0 / p.z());
}

void F2fFvon::add_label(const Eigen::Vector3d &p_in_cam, const Eigen::Vector2d &velocity) {
  OVTON_TON_CHECK(p_in_cam.allFinite() && velocity.allFinite(), "F2fFvon::add_label: non-finite label");
  OVTON_TON_CHECK(!options_.inverse_depth_input || p_in_cam.z() > 0, "F2fFvon::add_label: point behind the camera");
  positions_.push_back(input(p_in_cam));
  velocities_.push_back(velocity);
}

TrainReport F2fFvon::train() {
  if (positions_.empty())
    return last_report_ = TrainReport();
  pos_norm_.reset();
  vel_norm_.reset();
  for (size_t k = 0; k < positions_.size(); ++k) {
    pos_norm_.add(positions_[k]);
    vel_norm_.add(velocities_[k]);
  }
  pos_norm_.finish();
  vel_norm_.finish();
  data_.clear();
  for (size_t k = 0; k < positions_.size(); ++k)
    data_.push(pos_norm_.normalize(positions_[k]), vel_norm_.normalize(velocities_[k]));
  last_report_ = train_network(net_, adam_, data_, options_.train.for_call(calls_++));
  trained_ = true;
  return last_report_;
}

Eigen::Vector2d F2fFvon::predict(const Eigen::Vector3d &p_in_cam) const {
  OVTON_TON_CHECK(trained_, "F2fFvon::predict before train");
  OVTON_TON_CHECK(p_in_cam.allFinite(), "F2fFvon::predict: non-finite position");
  return vel_norm_.denormalize(net_.predict(pos_norm_.normalize(input(p_in_cam))));
}

} // namespace ton
} // namespace ovton::msckf
