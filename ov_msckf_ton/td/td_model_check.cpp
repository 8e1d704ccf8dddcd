#include "ov_msckf_ton/td/td_model_check.h"
#include "ov_msckf_ton/td/td_models.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace ovton::msckf {

TdTrendTest::TdTrendTest(double window_s, double z, double min_step_s)
    : window_s_(window_s), z_(z), min_step_s_(min_step_s), window_(2.0 * window_s) {}

void TdTrendTest::add(int64_t t_ns, double td_prior, double var_prior, double td_post, double var_post) {
  window_.add(t_ns, td_prior, var_prior, td_post, var_post);
}

TdTrendTest::Verdict TdTrendTest::evaluate() const {
  Verdict v;
  if (window_.empty())
    return v;
  const int64_t end = window_.last_ns();
  const TdCorrectionWindow::Sum now = window_.sum(end, window_s_);
  const TdCorrectionWindow::Sum before = window_.sum(end - static_cast<int64_t>(window_s_ * 1e9), window_s_);
  const auto contradicts = [&](const TdCorrectionWindow::Sum &w) {
    return w.covered && w.z() > z_ && std::abs(w.moved) > min_step_s_;
  };
  // Same sign in both stretches: a trend, not a filter converging by a jump or an outlier's kick.
  v.contradicted = contradicts(now) && contradicts(before) && (now.moved > 0) == (before.moved > 0);
  v.z = std::min(now.z(), before.z());
  v.moved_s = now.moved + before.moved;
  return v;
}

namespace {

class CheckedTdModel : public TdModel {
public:
  CheckedTdModel(std::unique_ptr<TdModel> inner, const TimeOffsetOptions &o)
      : inner_(std::move(inner)), opt_(o), test_(o.model_check_window_s, o.model_check_z, o.model_check_min_step_s) {}

  TdProcess kind() const override { return active().kind(); }
  void initialize(State &s) override { inner_->initialize(s); }
  double td_at_image(const State &s, int64_t t_cam_ns, int64_t last_image_ns) const override {
    return active().td_at_image(s, t_cam_ns, last_image_ns);
  }
  void propagate(State &s, double td_end, double dt_s) override {
    // The interval ends where the model that predicted td_end moves the mean; the switch takes the next one.
    active().propagate(s, td_end, dt_s);
    now_ns_ = s.t_imu_ns; // the image's updates follow: their corrections are stamped here
    if (pending_ && !drift_)
      switch_to_drift(s);
  }
  void after_update(double td0, double v0, double td1, double v1) override {
    active().after_update(td0, v0, td1, v1);
    if (!drift_)
      test_.add(now_ns_, td0, v0, td1, v1);
  }
  void after_image(const State &s, int64_t t_cam_ns) override {
    active().after_image(s, t_cam_ns);
    stats_ = active().stats();
    if (drift_) { // what TPN learned before the switch stays on record
      const TdModelStats &in = inner_->stats();
      stats_.learning_steps = in.learning_steps;
      stats_.tpn_first_label_image = in.tpn_first_label_image;
      stats_.tpn_first_prediction_image = in.tpn_first_prediction_image;
      stats_.tpn_label_restarts = in.tpn_label_restarts;
      stats_.rate_clamped = in.rate_clamped;
      stats_.propagations = in.propagations;
    }
    stats_.switched_ns = switched_ns_;
    stats_.check_z = check_z_;
    stats_.check_moved_s = check_moved_s_;
    if (drift_ || pending_)
      return;
    if (const TdTrendTest::Verdict v = test_.evaluate(); v.contradicted) {
      pending_ = true;
      check_z_ = v.z;
      check_moved_s_ = v.moved_s;
    }
  }

  const TdModel &inner() const { return *inner_; }

private:
  const TdModel &active() const { return drift_ ? *drift_ : *inner_; }
  TdModel &active() { return drift_ ? *drift_ : *inner_; }

  void switch_to_drift(State &s) {
    drift_ = make_drift_model(opt_);
    drift_->initialize(s);
    // What the corrections moved t_d by over the two stretches is how far the estimate trailed; it still trails by
    // about half of one stretch's worth, and the rate starts at that trend with its prior sigma around it.
    const double span_s = 2.0 * opt_.model_check_window_s;
    s.td_rate = check_moved_s_ / span_s;
    const double lag = 0.5 * check_moved_s_;
    const int d = s.td_index;
    s.for_each_covariance([&](auto &P) { P(d, d) += lag * lag; });
    switched_ns_ = s.t_imu_ns;
    pending_ = false;
  }

  std::unique_ptr<TdModel> inner_, drift_;
  TimeOffsetOptions opt_;
  TdTrendTest test_;
  int64_t now_ns_ = 0;
  bool pending_ = false;
  int64_t switched_ns_ = -1;
  double check_z_ = 0.0, check_moved_s_ = 0.0;
};

} // namespace

std::unique_ptr<TdModel> make_checked_model(std::unique_ptr<TdModel> inner, const TimeOffsetOptions &o) {
  return std::make_unique<CheckedTdModel>(std::move(inner), o);
}

const TdModel &unchecked_model(const TdModel &m) {
  const auto *c = dynamic_cast<const CheckedTdModel *>(&m);
  return c ? c->inner() : m;
}

std::string describe_model_check(const TdModelStats &st, int64_t first_ns, const TimeOffsetOptions &o) {
  if (st.switched_ns < 0)
    return "";
  std::ostringstream s;
  s << "t_d model check: switched to the drift state at " << (st.switched_ns - first_ns) * 1e-9
    << " s; the updates had moved t_d by " << st.check_moved_s * 1e3 << " ms in two stretches of "
    << o.model_check_window_s << " s, each more than " << st.check_z
    << " sigma of what they allowed: the offset moves faster than mode " << to_string(o.mode)
    << "'s model lets it (from there t_d's rate is estimated; its sigma includes how far it trailed)";
  return s.str();
}

} // namespace ovton::msckf
