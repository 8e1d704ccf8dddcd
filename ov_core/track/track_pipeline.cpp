#include "ov_core/track/track_pipeline.h"
#include "ov_core/types/errors.h"

#include <chrono>
#include <stdexcept>
#include <string>

namespace ovton::core {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

} // namespace

TrackPipeline::TrackPipeline(const std::vector<ImageEntry> &images, const CameraModel &camera,
                             const TrackKLTOptions &opt, ImageGetter get_image, size_t ahead)
    : TrackPipeline(images, TrackedStart{{}, std::make_unique<TrackKLT>(camera, opt)}, std::move(get_image), true,
                    ahead) {}

TrackPipeline::TrackPipeline(const std::vector<ImageEntry> &images, TrackedStart start, ImageGetter get_image,
                             bool threaded, size_t ahead)
    : images_(images), given_(std::move(start.frames)), threaded_(threaded), tracker_(std::move(start.tracker)),
      get_image_(std::move(get_image)), ahead_(ahead < 1 ? 1 : ahead), produced_(given_.size()) {
  if (!tracker_)
    throw std::logic_error("TrackPipeline: no tracker to go on with");
  if (given_.size() > images_.size())
    throw std::logic_error("TrackPipeline: more tracked images given than listed");
  if (threaded)
    thread_ = std::thread([this] { work(); });
}

TrackPipeline::~TrackPipeline() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable())
    thread_.join();
}

/// Runs on the tracking thread; an exception must not escape it, so it travels with its image to the consumer.
TrackedFrame TrackPipeline::track_caught(size_t index) {
  const ImageEntry &e = images_[index];
  TrackedFrame f;
  try {
    auto t0 = Clock::now();
    const cv::Mat gray = get_image_(index);
    f.wait_image_ms = ms_since(t0);
    if (gray.empty())
      throw DataError(e.path, "unreadable image (listed for stamp " + std::to_string(e.t_cam_ns) + ")");
    t0 = Clock::now();
    f.features = tracker_->track(e.t_cam_ns, gray);
    f.track_ms = ms_since(t0);
  } catch (...) {
    f.error = std::current_exception();
  }
  return f;
}

void TrackPipeline::work() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    cv_.wait(lock, [&] { return stop_ || (!failed_ && produced_ < images_.size() && ready_.size() < ahead_); });
    if (stop_)
      return;
    produce_locked(lock);
  }
}

void TrackPipeline::produce_locked(std::unique_lock<std::mutex> &lock) {
  const size_t index = produced_;
  lock.unlock();
  TrackedFrame f = track_caught(index); // on the thread: the work that overlaps the consumer's
  f.on_caller_thread = !threaded_;
  lock.lock();
  ++produced_;
  // Tracking cannot go on past an image it could not track: the tracks would jump the gap unnoticed.
  if (f.error) {
    failed_ = true;
    failure_ = f.error;
  }
  if (index >= next_take_)
    ready_.emplace(index, std::move(f));
  cv_.notify_all();
}

TrackedFrame TrackPipeline::take(const ImageEntry &e) {
  const auto index = entry_index(images_, e);
  if (!index)
    throw std::logic_error("TrackPipeline::take: the entry (" + e.path + ") is not one of the pipeline's images");
  return take(*index);
}

TrackedFrame TrackPipeline::take(size_t index) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (index >= images_.size() || index < next_take_)
    throw std::logic_error("TrackPipeline::take: image " + std::to_string(index) + " asked after " +
                           std::to_string(next_take_) + " of " + std::to_string(images_.size()));
  next_take_ = index;
  if (index < given_.size()) {
    TrackedFrame f;
    f.features = std::move(given_[index]);
    f.on_caller_thread = true; // nothing waited for
    next_take_ = index + 1;
    return f;
  }
  ready_.erase(ready_.begin(), ready_.lower_bound(index)); // skipped images: make room for the thread
  cv_.notify_all();
  if (!threaded_) // no thread: track up to this image here, through any the consumer skipped
    while (!failed_ && produced_ <= index)
      produce_locked(lock);
  cv_.wait(lock, [&] { return ready_.count(index) > 0 || (failed_ && produced_ <= index); });
  const auto it = ready_.find(index);
  if (it == ready_.end())
    std::rethrow_exception(failure_); // an image before this one, which the consumer skipped, stopped the tracking
  TrackedFrame f = std::move(it->second);
  ready_.erase(it);
  next_take_ = index + 1;
  cv_.notify_all();
  lock.unlock();
  if (f.error)
    std::rethrow_exception(f.error);
  return f;
}

} // namespace ovton::core
