#include "ov_msckf_ton/estimator/estimator.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/estimator/estimator_impl.h"

#include <algorithm>
#include <string>

namespace ovton {

namespace {

/// IMU kept before the first image arrives (a stream whose IMU runs long before its camera starts), and what the
/// stages keep from before the first image once it has (the search keeps a minute of it, init/td_search.h).
constexpr double kImuBeforeImagesS = 600.0, kImuBeforeFirstImageS = 61.0;

std::string stamp(int64_t t_ns) {
  return std::to_string(t_ns) + " ns";
}

} // namespace

Estimator::Impl::Impl(EstimatorSetup setup) : setup_(std::move(setup)), camera_(setup_.camera) {
  using msckf::TdMode;
  const msckf::VioOptions &o = setup_.options;
  msckf::validate_vio_options(o);
  if (setup_.max_queued_images < 1 || setup_.max_polled_states < 1)
    throw core::UsageError("Estimator: max_queued_images and max_polled_states must be >= 1");
  if (o.td.mode == TdMode::Oracle && !setup_.aids.td_truth)
    throw core::UsageError("mode oracle needs the true time offset (" + setup_.source + " has no td_truth/data.csv)");
  if (o.init.mode == msckf::InitMode::GroundTruth &&
      (setup_.aids.groundtruth.empty() || !setup_.aids.groundtruth.front().has_velocity))
    throw core::UsageError("ground-truth initialisation needs full-state ground truth in " + setup_.source);
  filter_opt_ = o;
  tracker_ = std::make_unique<core::TrackKLT>(camera_, o.track);
  for (const auto &c : setup_.more_cameras)
    secondary_.push_back(std::make_unique<core::TrackSecondary>(camera_, core::CameraModel(c), o.track));
  R_IC_ = core::camera_to_imu_rotation(setup_.camera, setup_.imu);
  prior_on_ = o.track.gyro_prior;
  if (prior_on_) {
    prior_imu_ = std::make_shared<core::ImuBuffer>();
    auto prior = std::make_shared<core::GyroRotationPrior>(prior_imu_, R_IC_, o.td.init_s);
    prior_td_ns_ = prior->imu_time(0);
    tracker_->set_rotation_prior(std::move(prior));
  }
  if (o.td.search.enabled && o.td.mode != TdMode::Off && o.td.mode != TdMode::Oracle) {
    search_ = std::make_unique<msckf::TdSearch>(setup_.camera, o.td.init_s, o.td.search);
  } else {
    search_done_ = true;
    status_.phase = EstimatorStatus::Phase::Initialising;
  }
  status_.td_s = o.td.init_s;
  status_.td_sigma_s = o.td.sigma_init_s;
}

Estimator::Impl::~Impl() {
  stop();
}

void Estimator::Impl::add_state_callback(StateCallback cb) {
  Lock lk(m_);
  if (started_)
    throw core::UsageError("Estimator: callbacks are added before the first feed");
  callbacks_.push_back(std::move(cb));
}

void Estimator::Impl::add_observer(std::shared_ptr<msckf::FilterObserver> observer) {
  Lock lk(m_);
  if (started_)
    throw core::UsageError("Estimator: observers are added before the first feed");
  if (!observer)
    throw core::UsageError("Estimator: a null observer");
  observers_.push_back(std::move(observer));
}

void Estimator::Impl::start_first_feed(Lock &lk) {
  (void)lk;
  if (eos_ || stopping_)
    throw core::UsageError("Estimator: fed after finish() or stop()");
  if (started_)
    return;
  started_ = true;
  if (setup_.threaded) {
    track_thread_ = std::thread([this] { stage_loop(true); });
    filter_thread_ = std::thread([this] { stage_loop(false); });
  }
}

void Estimator::Impl::rethrow_if_failed() const {
  if (error_)
    std::rethrow_exception(error_);
}

void Estimator::Impl::fail(Lock &lk, std::exception_ptr e) {
  (void)lk;
  if (!error_) {
    // A filter that failed after the coarse search found no offset most likely started at the wrong one: say so, with
    // what the search saw (an offset beyond its range reads "at the edge of the range").
    if (status_.td_search && !status_.td_search->found && status_.td_search->pairs > 0) {
      try {
        std::rethrow_exception(e);
      } catch (const core::EstimatorFailure &f) {
        e = std::make_exception_ptr(core::EstimatorFailure(
            f.t_ns(), std::string(f.what()) + "; the coarse t_d search had found no offset (" + status_.td_search->why +
                          "): give an initial t_d near the true one or widen time_offset.search_range_s"));
      } catch (...) {
      }
    }
    error_ = e;
    status_.phase = EstimatorStatus::Phase::Stopped;
    try {
      std::rethrow_exception(e);
    } catch (const std::exception &x) {
      status_.stop_reason = x.what();
    } catch (...) {
      status_.stop_reason = "unknown error";
    }
  }
  cv_.notify_all();
}

void Estimator::Impl::feed_imu(const core::ImuData &m) {
  Lock lk(m_);
  rethrow_if_failed();
  if (!m.wm.allFinite() || !m.am.allFinite())
    throw core::UsageError("IMU reading at " + stamp(m.t_imu_ns) + " is not finite");
  if (status_.imu_received > 0 && m.t_imu_ns <= last_imu_ns_)
    throw core::UsageError("IMU readings must arrive in increasing time order (" + stamp(m.t_imu_ns) + " after " +
                           stamp(last_imu_ns_) + ")");
  start_first_feed(lk);
  imu_.push_back(m);
  last_imu_ns_ = m.t_imu_ns;
  ++status_.imu_received;
  if (status_.images_received == 0)
    while (imu_.size() > 2 && imu_.back().t_imu_ns - imu_.front().t_imu_ns > core::s_to_ns(kImuBeforeImagesS)) {
      imu_.pop_front();
      ++imu_base_;
    }
  cv_.notify_all();
  if (!setup_.threaded)
    pump(lk);
  rethrow_if_failed();
}

void Estimator::Impl::feed_image(int64_t t_cam_ns, const cv::Mat &gray, std::vector<core::PointObservation> obs,
                                 bool feature_level, std::vector<cv::Mat> more) {
  if (more.size() > setup_.more_cameras.size())
    throw core::UsageError("image at " + stamp(t_cam_ns) + " comes with " + std::to_string(more.size()) +
                           " further cameras' images; the setup has " + std::to_string(setup_.more_cameras.size()));
  for (size_t k = 0; k < more.size(); ++k) {
    const core::CameraCalib &c = setup_.more_cameras[k];
    if (!more[k].empty() && (more[k].type() != CV_8UC1 || more[k].cols != c.width || more[k].rows != c.height))
      throw core::UsageError("camera " + std::to_string(k + 1) + "'s image at " + stamp(t_cam_ns) +
                             " is not 8-bit gray of " + std::to_string(c.width) + "x" + std::to_string(c.height));
  }
  if (!feature_level &&
      (gray.type() != CV_8UC1 || gray.cols != setup_.camera.width || gray.rows != setup_.camera.height))
    throw core::UsageError("image at " + stamp(t_cam_ns) + " is " + std::to_string(gray.cols) + "x" +
                           std::to_string(gray.rows) + (gray.type() == CV_8UC1 ? "" : " and not 8-bit gray") +
                           "; the camera's images are " + std::to_string(setup_.camera.width) + "x" +
                           std::to_string(setup_.camera.height) + " 8-bit gray");
  Lock lk(m_);
  rethrow_if_failed();
  if (status_.images_received > 0 && t_cam_ns <= last_image_ns_)
    throw core::UsageError("image stamps must increase (" + stamp(t_cam_ns) + " after " + stamp(last_image_ns_) + ")");
  start_first_feed(lk);
  if (status_.images_received == 0) {
    // Deterministic from here on: what the stages keep from before the first image depends on its stamp only.
    const int64_t keep_from =
        core::saturating_add_ns(t_cam_ns, core::s_to_ns(setup_.options.td.init_s - kImuBeforeFirstImageS));
    while (!imu_.empty() && imu_.front().t_imu_ns < keep_from) {
      imu_.pop_front();
      ++imu_base_;
    }
    track_imu_next_ = std::max(track_imu_next_, imu_base_);
    filter_imu_next_ = std::max(filter_imu_next_, imu_base_);
  }
  if (setup_.threaded)
    cv_.wait(lk, [&] { return inputs_.size() < setup_.max_queued_images || track_waits_imu_ || error_ || stopping_; });
  rethrow_if_failed();
  last_image_ns_ = t_cam_ns;
  ++status_.images_received;
  inputs_.push_back({t_cam_ns, gray, std::move(more), std::move(obs), feature_level, Clock::now()});
  cv_.notify_all();
  if (!setup_.threaded)
    pump(lk);
  rethrow_if_failed();
}

void Estimator::Impl::pump(Lock &lk) {
  try {
    while (!error_ && !stopping_) {
      const bool tracked = track_step(lk);
      const bool filtered = filter_step(lk);
      if (!tracked && !filtered)
        break;
    }
  } catch (...) {
    fail(lk, std::current_exception());
  }
}

void Estimator::Impl::stage_loop(bool tracking) {
  Lock lk(m_);
  try {
    while (!error_ && !stopping_ && !(tracking ? tracking_done_ : filter_done_))
      if (!(tracking ? track_step(lk) : filter_step(lk)))
        cv_.wait(lk);
  } catch (...) {
    fail(lk, std::current_exception());
  }
}

size_t Estimator::Impl::poll(std::vector<core::StateSample> &out) {
  Lock lk(m_);
  const size_t n = polled_.size();
  out.insert(out.end(), polled_.begin(), polled_.end());
  polled_.clear();
  return n;
}

EstimatorStatus Estimator::Impl::status() const {
  Lock lk(m_);
  return status_;
}

void Estimator::Impl::finish() {
  Lock lk(m_);
  rethrow_if_failed();
  if (stopping_)
    throw core::UsageError("Estimator: finish() after stop()");
  eos_ = true;
  cv_.notify_all();
  if (setup_.threaded) {
    lk.unlock();
    if (track_thread_.joinable())
      track_thread_.join();
    if (filter_thread_.joinable())
      filter_thread_.join();
    lk.lock();
  }
  started_ = true;
  // Unthreaded, or nothing was ever fed (no threads were started): the stages run here.
  pump(lk);
  rethrow_if_failed();
  status_.phase = EstimatorStatus::Phase::Finished;
  if (status_.states_out == 0)
    throw core::DataError(setup_.source, "no pose was estimated from " + std::to_string(status_.images_processed) +
                                             " images (" + std::to_string(status_.images_skipped) +
                                             " beyond the IMU log); initialisation: " + status_.init_message);
}

void Estimator::Impl::stop() {
  Lock lk(m_);
  stopping_ = true;
  if (!error_ && status_.phase != EstimatorStatus::Phase::Finished) {
    status_.phase = EstimatorStatus::Phase::Stopped;
    status_.stop_reason = "stopped by the caller";
  }
  cv_.notify_all();
  lk.unlock();
  if (track_thread_.joinable())
    track_thread_.join();
  if (filter_thread_.joinable())
    filter_thread_.join();
}

EstimatorReport Estimator::Impl::report() const {
  Lock lk(m_);
  EstimatorReport r;
  if (vio_) {
    r.counters = vio_->counters();
    r.times = vio_->times();
    r.acceptance = vio_->health().total();
    r.td_model = vio_->td_model().stats();
  }
  (setup_.threaded ? r.times.tracking_thread : r.times.tracking) += tracking_ms_;
  r.init_message = status_.init_message;
  r.td_search = status_.td_search;
  r.images_skipped = status_.images_skipped;
  r.latency_ms = latency_ms_;
  return r;
}

Estimator::Estimator(EstimatorSetup setup) : impl_(std::make_unique<Impl>(std::move(setup))) {}
Estimator::~Estimator() = default;
void Estimator::add_state_callback(StateCallback cb) {
  impl_->add_state_callback(std::move(cb));
}
void Estimator::add_observer(std::shared_ptr<msckf::FilterObserver> observer) {
  impl_->add_observer(std::move(observer));
}
void Estimator::feed_imu(const core::ImuData &m) {
  impl_->feed_imu(m);
}
void Estimator::feed_image(int64_t t_cam_ns, const cv::Mat &gray) {
  impl_->feed_image(t_cam_ns, gray, {}, false);
}
void Estimator::feed_images(int64_t t_cam_ns, const std::vector<cv::Mat> &grays) {
  if (grays.empty())
    throw core::UsageError("feed_images: no image");
  impl_->feed_image(t_cam_ns, grays.front(), {}, false, std::vector<cv::Mat>(grays.begin() + 1, grays.end()));
}
void Estimator::feed_features(int64_t t_cam_ns, std::vector<core::PointObservation> observations) {
  impl_->feed_image(t_cam_ns, cv::Mat(), std::move(observations), true);
}
size_t Estimator::camera_count() const {
  return impl_->camera_count();
}
size_t Estimator::poll(std::vector<core::StateSample> &out) {
  return impl_->poll(out);
}
EstimatorStatus Estimator::status() const {
  return impl_->status();
}
void Estimator::finish() {
  impl_->finish();
}
void Estimator::stop() {
  impl_->stop();
}
EstimatorReport Estimator::report() const {
  return impl_->report();
}

} // namespace ovton
