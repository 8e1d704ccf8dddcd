// Constant and random-walk time offset: the mean stays where the updates put it, the variance grows by q²·dt.
#include "ov_msckf_ton/td/td_models.h"
#include "ov_msckf_ton/td/td_noise_adapter.h"

#include <optional>

namespace ovton::msckf {

namespace {

class RandomWalkTdModel : public TdModel {
public:
  RandomWalkTdModel(double q, bool adaptive, double block_s) : q_(q) {
    if (adaptive)
      adapter_.emplace(q, block_s);
    stats_.process_sigma = q;
  }
  TdProcess kind() const override { return q_ > 0 || adapter_ ? TdProcess::RandomWalk : TdProcess::Constant; }
  double td_at_image(const State &s, int64_t, int64_t) const override { return s.td; }
  void propagate(State &s, double, double dt_s) override {
    const double q = adapter_ ? adapter_->q() : q_;
    if (q > 0)
      propagate_td_covariance(s, q, 0.0, dt_s);
    if (adapter_ && dt_s > 0)
      adapter_->add_process(q * q * dt_s);
    dt_since_image_ += dt_s;
  }
  void after_update(double td0, double v0, double td1, double v1) override {
    if (adapter_)
      adapter_->add_update(td0, v0, td1, v1);
  }
  void after_image(const State &, int64_t) override {
    if (adapter_) {
      adapter_->close_image(dt_since_image_);
      stats_.process_sigma = adapter_->q();
    }
    dt_since_image_ = 0.0;
  }

private:
  double q_;
  std::optional<TdNoiseAdapter> adapter_;
  double dt_since_image_ = 0.0;
};

} // namespace

std::unique_ptr<TdModel> make_random_walk_model(double q, bool adaptive, double block_s) {
  return std::make_unique<RandomWalkTdModel>(q, adaptive, block_s);
}

} // namespace ovton::msckf
