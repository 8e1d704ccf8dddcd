// Drift state: t_d and its rate ṫ_d in the filter, the paper's eq. 4 (t_d(k) = t_d(k−1) + t_bias + n_td) as a
// Kalman process model. Beyond the paper: where TPN learns the trend from the filter's own estimates and feeds it
// back as a fixed drive, here the rate is a state variable that every update corrects, with its own covariance,
// so the trend and its uncertainty come from the measurements themselves.
#include "ov_core/types/sensor_data.h"
#include "ov_msckf_ton/td/td_models.h"
#include "ov_msckf_ton/td/td_noise_adapter.h"

#include <optional>

namespace ovton::msckf {

namespace {

class DriftTdModel : public TdModel {
public:
  explicit DriftTdModel(const TimeOffsetOptions &o)
      : q_td_(o.random_walk), q_rate_(o.rate_random_walk), sigma_rate0_(o.rate_sigma_init) {
    if (o.adaptive_noise)
      adapter_.emplace(o.random_walk, o.adaptive_block_s);
    stats_.process_sigma = q_td_;
  }
  TdProcess kind() const override { return TdProcess::Drift; }

  void initialize(State &s) override {
    s.td_rate = 0.0;
    s.td_rate_index = s.add_variable(Eigen::MatrixXd::Constant(1, 1, sigma_rate0_ * sigma_rate0_));
  }

  /// The propagation ends at t_imu = t_cam + t_d(end) and t_d moves at ṫ_d over it:
  ///   t_d(end) = t_d + ṫ_d·(t_cam + t_d(end) − t_state)  =>  t_d(end) = (t_d + ṫ_d·(t_cam − t_state)) / (1 − ṫ_d).
  double td_at_image(const State &s, int64_t t_cam_ns, int64_t) const override {
    if (s.td_rate_index < 0 || s.td_rate == 0.0)
      return s.td;
    const double dt = ovton::core::ns_to_s(t_cam_ns - s.t_imu_ns);
    return (s.td + s.td_rate * dt) / (1.0 - s.td_rate);
  }

  void propagate(State &s, double, double dt_s) override {
    if (!(dt_s > 0))
      return;
    s.td += s.td_rate * dt_s;
    const double q = adapter_ ? adapter_->q() : q_td_;
    propagate_td_covariance(s, q, q_rate_, dt_s);
    if (adapter_)
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
  double q_td_, q_rate_, sigma_rate0_;
  std::optional<TdNoiseAdapter> adapter_;
  double dt_since_image_ = 0.0;
};

} // namespace

std::unique_ptr<TdModel> make_drift_model(const TimeOffsetOptions &o) {
  return std::make_unique<DriftTdModel>(o);
}

} // namespace ovton::msckf
