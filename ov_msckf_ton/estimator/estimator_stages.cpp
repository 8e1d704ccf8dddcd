// The estimator's two stages (estimator_impl.h). Each step is called with the lock held, decides what it can do from
// the queues, and releases the lock for the work itself (tracking an image, judging the search's window, filtering an
// image) — so that feeding, polling and the other stage go on meanwhile.
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/estimator/estimator_impl.h"

#include <algorithm>
#include <limits>

namespace ovton {

namespace {

double ms_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

} // namespace

bool Estimator::Impl::imu_past_for_tracking(Lock &lk, int64_t t_imu_ns) {
  (void)lk;
  if (!eos_ && !(status_.imu_received > 0 && last_imu_ns_ > t_imu_ns))
    return false;
  track_imu_next_ = std::max(track_imu_next_, imu_base_);
  const bool to_search = search_ && !search_->done();
  while (track_imu_next_ < imu_base_ + imu_.size()) {
    if (track_imu_handed_ && track_last_handed_ns_ > t_imu_ns)
      break; // the first reading after t_imu_ns is handed over already
    const core::ImuData &m = imu_[track_imu_next_ - imu_base_];
    if (to_search)
      search_->add_imu(m);
    if (prior_on_)
      prior_imu_->push(m);
    track_imu_handed_ = true;
    track_last_handed_ns_ = m.t_imu_ns;
    ++track_imu_next_;
  }
  return true;
}

bool Estimator::Impl::track_step(Lock &lk) {
  if (tracking_done_)
    return false;
  if (inputs_.empty()) {
    if (!eos_)
      return false;
    // The end of the stream: the search decides on what it has.
    if (search_ && !search_->done()) {
      imu_past_for_tracking(lk, std::numeric_limits<int64_t>::max());
      lk.unlock();
      while (!search_->decide(true)) {
      }
      lk.lock();
      release_search(lk);
    }
    tracking_done_ = true;
    cv_.notify_all();
    return true;
  }
  const int64_t t_cam_ns = inputs_.front().t_cam_ns;
  // The search judges its window before an image past it is tracked: what it finds moves the gyro prior's offset.
  if (search_ && !search_->done() && search_->must_decide_before(t_cam_ns)) {
    if (!imu_past_for_tracking(lk, search_->imu_needed_ns())) {
      track_waits_imu_ = true;
      cv_.notify_all();
      return false;
    }
    lk.unlock();
    const bool decided = search_->decide(false);
    lk.lock();
    if (decided)
      release_search(lk);
    return true;
  }
  if (prior_on_ && !imu_past_for_tracking(lk, core::saturating_add_ns(t_cam_ns, prior_td_ns_))) {
    track_waits_imu_ = true;
    cv_.notify_all();
    return false;
  }
  track_waits_imu_ = false;
  // Back-pressure: the filter's queue is full and the filter is not waiting for the IMU.
  if (setup_.threaded && search_done_ && tracked_.size() >= setup_.max_queued_images && !filter_waits_imu_ && !eos_)
    return false;
  Input in = std::move(inputs_.front());
  inputs_.pop_front();
  cv_.notify_all(); // a caller may wait for room
  lk.unlock();
  const auto t0 = Clock::now();
  Tracked out{in.t_cam_ns, track(in), track_more(in), in.arrived};
  const double ms = ms_between(t0, Clock::now());
  if (!in.feature_level)
    for (const auto &o : observers_)
      o->on_image(in.t_cam_ns, in.gray);
  lk.lock();
  tracking_ms_ += ms;
  // The next image's rotation starts at this one, at an offset the search may still move by its range.
  if (prior_on_)
    prior_imu_->drop_before(
        core::saturating_add_ns(in.t_cam_ns, prior_td_ns_ - core::s_to_ns(setup_.options.td.search.range_s + 0.1)));
  if (search_ && !search_->done()) {
    search_->add_frame(out.t_cam_ns, msckf::bearings_of(out.features));
    held_.push_back(std::move(out));
  } else {
    tracked_.push_back(std::move(out));
  }
  trim_imu();
  cv_.notify_all();
  return true;
}

std::vector<core::TrackedFeature> Estimator::Impl::track(const Input &in) {
  if (!in.feature_level)
    return tracker_->track(in.t_cam_ns, in.gray);
  std::vector<core::TrackedFeature> out;
  out.reserve(in.observations.size());
  for (const auto &o : in.observations)
    out.push_back({o.id, o.uv, camera_.undistort(o.uv)});
  return out;
}

std::vector<std::vector<core::TrackedFeature>> Estimator::Impl::track_more(const Input &in) {
  std::vector<std::vector<core::TrackedFeature>> out(secondary_.size());
  for (size_t k = 0; k < secondary_.size() && k < in.more.size(); ++k)
    if (!in.more[k].empty())
      out[k] = secondary_[k]->track(in.t_cam_ns, in.more[k], *tracker_);
  return out;
}

void Estimator::Impl::release_search(Lock &lk) {
  (void)lk;
  const msckf::TdSearchResult &r = search_->result();
  status_.td_search = r;
  if (r.found) {
    filter_opt_.td.init_s = r.td_s;
    // The filter's prior must cover the search's own error.
    filter_opt_.td.sigma_init_s = std::max(filter_opt_.td.sigma_init_s, 3 * r.sigma_s);
    status_.td_s = r.td_s;
    status_.td_sigma_s = filter_opt_.td.sigma_init_s;
    if (prior_on_) {
      auto prior = std::make_shared<core::GyroRotationPrior>(prior_imu_, R_IC_, r.td_s);
      prior_td_ns_ = prior->imu_time(0);
      tracker_->set_rotation_prior(std::move(prior));
    }
  }
  for (auto &f : held_)
    tracked_.push_back(std::move(f));
  held_.clear();
  search_done_ = true;
  status_.phase = EstimatorStatus::Phase::Initialising;
  trim_imu();
  cv_.notify_all();
}

bool Estimator::Impl::filter_step(Lock &lk) {
  if (filter_done_ || !search_done_)
    return false;
  if (!vio_) {
    lk.unlock();
    auto vio = std::make_unique<msckf::VioManager>(
        filter_opt_, setup_.camera, setup_.imu, setup_.aids, [this](const core::StateSample &s) { on_state(s); },
        observers_, setup_.more_cameras);
    lk.lock();
    vio_ = std::move(vio);
    return true;
  }
  if (tracked_.empty()) {
    if (!tracking_done_)
      return false;
    filter_done_ = true;
    cv_.notify_all();
    return true;
  }
  const Tracked &f = tracked_.front();
  // Which readings go before this image: every one up to its IMU-clock time plus the filter's look-ahead, and one
  // more if none reaches the image itself (it then interpolates instead of extrapolating). They must all have
  // arrived, which the first reading past them shows.
  const double td_s = vio_->td_for_image_s(f.t_cam_ns);
  const auto t_imu = core::try_imu_time_ns(f.t_cam_ns, td_s);
  if (!t_imu)
    throw core::UsageError("image at " + std::to_string(f.t_cam_ns) + " ns with t_d " + std::to_string(td_s) +
                           " s has no IMU-clock time in the int64 ns clock");
  const int64_t need = core::saturating_add_ns(*t_imu, vio_->imu_lookahead_ns());
  if (!eos_ && !(status_.imu_received > 0 && last_imu_ns_ > need)) {
    filter_waits_imu_ = true;
    cv_.notify_all();
    return false;
  }
  filter_waits_imu_ = false;
  std::vector<core::ImuData> readings;
  filter_imu_next_ = std::max(filter_imu_next_, imu_base_);
  const size_t end = imu_base_ + imu_.size();
  while (filter_imu_next_ < end && imu_[filter_imu_next_ - imu_base_].t_imu_ns <= need)
    readings.push_back(imu_[filter_imu_next_++ - imu_base_]);
  const auto last_fed = [&]() -> std::optional<int64_t> {
    if (!readings.empty())
      return readings.back().t_imu_ns;
    return filter_fed_any_ ? std::optional<int64_t>(filter_last_fed_ns_) : std::nullopt;
  };
  if (filter_imu_next_ < end && (!last_fed() || *last_fed() < *t_imu))
    readings.push_back(imu_[filter_imu_next_++ - imu_base_]);
  const bool covered = last_fed() && *last_fed() >= *t_imu;
  if (!readings.empty()) {
    filter_fed_any_ = true;
    filter_last_fed_ns_ = readings.back().t_imu_ns;
  }
  Tracked frame = std::move(tracked_.front());
  tracked_.pop_front();
  trim_imu();
  cv_.notify_all(); // the tracking stage may wait for room
  current_arrival_ = frame.arrived;
  lk.unlock();
  for (const auto &m : readings)
    vio_->on_imu(m);
  if (covered)
    vio_->process_frame(frame.t_cam_ns, frame.features, frame.more);
  lk.lock();
  if (covered)
    ++status_.images_processed;
  else
    ++status_.images_skipped; // no IMU reading reaches it: it cannot be used
  status_.initialized = vio_->initialized();
  status_.init_message = vio_->init_message();
  return true;
}

void Estimator::Impl::on_state(const core::StateSample &s) {
  {
    Lock lk(m_);
    latency_ms_.push_back(ms_between(current_arrival_, Clock::now()));
    polled_.push_back(s);
    while (polled_.size() > setup_.max_polled_states)
      polled_.pop_front();
    ++status_.states_out;
    status_.td_s = s.td_s;
    status_.td_sigma_s = s.td_sigma_s;
    status_.phase = EstimatorStatus::Phase::Running;
  }
  for (const auto &cb : callbacks_)
    cb(s);
}

void Estimator::Impl::trim_imu() {
  size_t keep = filter_imu_next_;
  if (tracking_uses_imu())
    keep = std::min(keep, track_imu_next_);
  while (imu_base_ < keep && !imu_.empty()) {
    imu_.pop_front();
    ++imu_base_;
  }
}

} // namespace ovton
