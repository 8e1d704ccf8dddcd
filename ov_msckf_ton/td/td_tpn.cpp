// The paper's TPN in the filter (Sec. IV-C, eq. 14, Algorithm 1 stages 3-4): after each image the filter's estimate
// t̂_d(K−1) is a label, the network predicts t_d^TPN(K), and the propagation to image K moves the mean at
// J_td = (t_d^TPN(K) − t̂_d(K−1)) / dt, bounded by rate_max; t_d carries random-walk noise. With
// ton.tpn_label_images M > 1 a label is the mean of M images' estimates and J_td = (t_d^TPN − last label) / the
// labels' spacing, held until the next label.
#include "ov_core/types/sensor_data.h"
#include "ov_msckf_ton/td/td_model_check.h"
#include "ov_msckf_ton/td/td_models.h"
#include "ov_msckf_ton/td/td_noise_adapter.h"

#include <optional>
#include <sstream>

namespace ovton::msckf {

namespace {

class TpnTdModel : public TdModel {
public:
  TpnTdModel(const TimeOffsetOptions &o, const TonOptions &ton)
      : driver_(ton.tpn), q_(o.random_walk_tpn), start_sigma_s_(ton.tpn_start_sigma_s),
        label_images_(ton.tpn_label_images), clone_trend_(o.clone_trend), trend_tau_s_(o.clone_trend_tau_s) {
    if (o.adaptive_noise)
      adapter_.emplace(o.random_walk_tpn, o.adaptive_block_s);
    stats_.process_sigma = q_;
  }
  TdProcess kind() const override { return TdProcess::Tpn; }
  const TpnDriver &driver() const { return driver_; }

  /// Paper eq. 14 with dt the time between images: the mean reaches t_d^TPN(K) (or the bounded step towards it)
  /// exactly at this image.
  double td_at_image(const State &s, int64_t t_cam_ns, int64_t last_image_ns) const override {
    last_clamped_ = false;
    if (last_image_ns < 0 || t_cam_ns <= last_image_ns)
      return s.td;
    const double dt = ovton::core::ns_to_s(t_cam_ns - last_image_ns);
    if (label_images_ == 1)
      return s.td + driver_.rate(s.td, dt, &last_clamped_) * dt;
    // Block labels: the rate from the last label to the predicted next one, over their spacing.
    if (!(label_spacing_s_ > 0))
      return s.td;
    return s.td + driver_.rate(last_label_, label_spacing_s_, &last_clamped_) * dt;
  }

  void propagate(State &s, double td_end, double dt_s) override {
    stats_.rate_clamped += last_clamped_ ? 1 : 0;
    stats_.propagations += dt_s > 0 ? 1 : 0;
    last_clamped_ = false;
    // The IMU-clock interval differs from the camera interval by the change in t_d itself: the rate is taken over
    // the interval actually propagated.
    const double rate = dt_s > 0 ? (td_end - s.td) / dt_s : 0.0;
    s.td += rate * dt_s;
    if (clone_trend_ && dt_s > 0) {
      // Older clones' rows (State::td_offset_at) at a rate averaged over trend_tau_s: the rows move t̂_d, t̂_d's
      // history is TPN's labels, and the labels set the rate, so an unsmoothed rate feeds back on itself.
      trend_ = trend_tau_s_ > 0 ? trend_ + dt_s / (trend_tau_s_ + dt_s) * (rate - trend_) : rate;
      s.td_rate = trend_;
    }
    const double q = adapter_ ? adapter_->q() : q_;
    propagate_td_covariance(s, q, 0.0, dt_s);
    if (adapter_ && dt_s > 0)
      adapter_->add_process(q * q * dt_s);
    dt_since_image_ += dt_s;
  }

  void after_update(double td0, double v0, double td1, double v1) override {
    if (adapter_)
      adapter_->add_update(td0, v0, td1, v1);
  }

  void after_image(const State &s, int64_t t_cam_ns) override {
    if (adapter_) {
      adapter_->close_image(dt_since_image_);
      stats_.process_sigma = adapter_->q();
    }
    dt_since_image_ = 0.0;
    ++images_;
    // The labels are the filter's own estimates: while t_d is still converging (σ above tpn_start_sigma_s) they
    // trace the convergence transient, not the offset's motion, and a network trained on them extrapolates the
    // transient: on a constant offset t_d then overshoots and the trajectory can diverge (docs/ton.md).
    if (s.td_sigma() > start_sigma_s_) {
      // Converging again: the block labels start over, and t_d is not driven at the last labels' rate meanwhile.
      start_block();
      if (stats_.tpn_first_label_image > 0 && !restarting_) {
        ++stats_.tpn_label_restarts;
        restarting_ = true;
      }
      if (label_images_ > 1 && has_label_) {
        has_label_ = false;
        label_spacing_s_ = 0.0;
        driver_.clear_labels();
      }
      return;
    }
    restarting_ = false;
    if (stats_.tpn_first_label_image < 0)
      stats_.tpn_first_label_image = images_;
    if (label_images_ == 1) {
      learned(driver_.step(s.td));
      return;
    }
    if (first_image_ns_ < 0)
      first_image_ns_ = t_cam_ns;
    block_td_ += s.td;
    block_t_ += ovton::core::ns_to_s(t_cam_ns - first_image_ns_);
    if (++block_n_ < label_images_)
      return;
    const double label = block_td_ / block_n_, t_label = block_t_ / block_n_;
    label_spacing_s_ = has_label_ ? t_label - last_label_t_ : 0.0;
    last_label_ = label;
    last_label_t_ = t_label;
    has_label_ = true;
    start_block();
    learned(driver_.step(label));
  }

private:
  void learned(bool predicts) {
    ++stats_.learning_steps;
    if (predicts && stats_.tpn_first_prediction_image < 0)
      stats_.tpn_first_prediction_image = images_;
  }
  void start_block() {
    block_n_ = 0;
    block_td_ = block_t_ = 0.0;
  }

  TpnDriver driver_;
  double q_, start_sigma_s_;
  std::optional<TdNoiseAdapter> adapter_;
  double dt_since_image_ = 0.0;
  mutable bool last_clamped_ = false;
  // Block labels (label_images_ > 1): the running block and the last label, times in seconds from the first image.
  int label_images_ = 1, block_n_ = 0;
  bool clone_trend_ = false;
  double trend_tau_s_ = 0.0, trend_ = 0.0;
  double block_td_ = 0.0, block_t_ = 0.0;
  double last_label_ = 0.0, last_label_t_ = 0.0, label_spacing_s_ = 0.0;
  bool has_label_ = false, restarting_ = false;
  int64_t first_image_ns_ = -1;
  long images_ = 0;
};

} // namespace

std::unique_ptr<TdModel> make_tpn_model(const TimeOffsetOptions &o, const TonOptions &ton) {
  return std::make_unique<TpnTdModel>(o, ton);
}

std::string describe_tpn_learning(const TdModelStats &st, double rate_max_s_per_s) {
  if (st.tpn_first_label_image < 0 && st.learning_steps == 0)
    return "";
  std::ostringstream s;
  s << "TPN: labels from image " << st.tpn_first_label_image << ", first prediction after image ";
  if (st.tpn_first_prediction_image < 0)
    s << "(none)";
  else
    s << st.tpn_first_prediction_image;
  s << " (t_d a random walk until then); " << st.learning_steps << " trainings, labels restarted "
    << st.tpn_label_restarts << " times; rate at its bound (time_offset.rate_max " << rate_max_s_per_s * 1e3
    << " ms/s) in " << st.rate_clamped << " of " << st.propagations << " propagations";
  return s.str();
}

const TpnDriver *tpn_driver_of(const TdModel &m) {
  const auto *t = dynamic_cast<const TpnTdModel *>(&unchecked_model(m));
  return t ? &t->driver() : nullptr;
}

} // namespace ovton::msckf
