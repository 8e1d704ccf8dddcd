#include "ov_core/io/image_prefetcher.h"
#include "ov_core/io/image_store.h"

namespace ov_core {
namespace {

cv::Mat decode(const ImageEntry &e) {
  return e.features ? cv::Mat() : load_image(e);
}

/// Decodes on the worker thread; what the decoder throws (a corrupt bag message) is kept for the consumer, who rethrows
/// it when it asks for that image: an exception must not escape the thread.
ImagePrefetcher::Decoded decode_caught(const ImageEntry &e) {
  ImagePrefetcher::Decoded d;
  try {
    d.image = decode(e);
  } catch (...) {
    d.error = std::current_exception();
  }
  return d;
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
    Decoded m = decode_caught(images_[index]); // the work that overlaps the consumer's
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
      Decoded m = std::move(it->second);
      ready_.erase(it);
      wanted_ = index + 1;
      cv_.notify_all();
      lock.unlock();
      if (m.error)
        std::rethrow_exception(m.error);
      return m.image;
    }
  }
  lock.unlock(); // asked again for an index already taken or dropped: decode here
  return decode(images_[index]);
}

} // namespace ov_core
