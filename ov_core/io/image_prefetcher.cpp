#include "ov_core/io/image_prefetcher.h"

#include <opencv2/imgcodecs.hpp>

namespace ov_core {
namespace {

cv::Mat decode(const ImageEntry &e) {
  return e.features ? cv::Mat() : cv::imread(e.path, cv::IMREAD_GRAYSCALE);
}

} // namespace

ImagePrefetcher::ImagePrefetcher(const std::vector<ImageEntry> &images, size_t ahead)
    : images_(images), ahead_(ahead < 1 ? 1 : ahead), thread_([this] { work(); }) {}

ImagePrefetcher::~ImagePrefetcher() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void ImagePrefetcher::work() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    cv_.wait(lock, [&] { return stop_ || (std::max(produced_, wanted_) < images_.size() && ready_.size() < ahead_); });
    if (stop_)
      return;
    const size_t index = produced_ = std::max(produced_, wanted_); // skip what the consumer has passed
    ++produced_;
    in_flight_ = index;
    lock.unlock();
    cv::Mat m = decode(images_[index]); // the work that overlaps the consumer's
    lock.lock();
    in_flight_ = std::numeric_limits<size_t>::max();
    if (index >= wanted_)
      ready_.emplace(index, std::move(m));
    cv_.notify_all();
  }
}

cv::Mat ImagePrefetcher::get(const ImageEntry &e) {
  const ImageEntry *begin = images_.data(), *end = begin + images_.size();
  return &e >= begin && &e < end ? get(static_cast<size_t>(&e - begin)) : decode(e);
}

cv::Mat ImagePrefetcher::get(size_t index) {
  if (index >= images_.size())
    return cv::Mat();
  std::unique_lock<std::mutex> lock(mutex_);
  if (index >= wanted_) {
    wanted_ = index;
    ready_.erase(ready_.begin(), ready_.lower_bound(index)); // skipped images
    cv_.notify_all();
    // Decoded, being decoded, or next in line: wait for it.
    cv_.wait(lock, [&] { return ready_.count(index) > 0 || (in_flight_ != index && produced_ > index); });
    const auto it = ready_.find(index);
    if (it != ready_.end()) {
      cv::Mat m = std::move(it->second);
      ready_.erase(it);
      wanted_ = index + 1;
      cv_.notify_all();
      return m;
    }
  }
  lock.unlock(); // asked again for an index already taken or dropped: decode here
  return decode(images_[index]);
}

} // namespace ov_core
