#include "ov_core/io/image_prefetcher.h"
#include "ov_core/io/image_store.h"

namespace ovton::core {
namespace {

cv::Mat decode_entry(const ImageEntry &e) {
  return e.features ? cv::Mat() : load_image(e);
}

} // namespace

ImagePrefetcher::ImagePrefetcher(const std::vector<ImageEntry> &images, size_t ahead,
                                 std::shared_ptr<const DecodedImages> given)
    : images_(images), ahead_(ahead < 1 ? 1 : ahead), given_(std::move(given)), thread_([this] { work(); }) {}

cv::Mat ImagePrefetcher::decode(size_t index) const {
  if (given_)
    if (const auto it = given_->find(index); it != given_->end())
      return it->second;
  return decode_entry(images_[index]);
}

/// Decodes on the worker thread; what the decoder throws (a corrupt bag message) is kept for the consumer, who rethrows
/// it when it asks for that image: an exception must not escape the thread.
ImagePrefetcher::Decoded ImagePrefetcher::decode_caught(size_t index) const {
  Decoded d;
  try {
    d.image = decode(index);
  } catch (...) {
    d.error = std::current_exception();
  }
  return d;
}

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
    Decoded m = decode_caught(index); // the work that overlaps the consumer's
    lock.lock();
    in_flight_ = std::numeric_limits<size_t>::max();
    if (index >= wanted_)
      ready_.emplace(index, std::move(m));
    cv_.notify_all();
  }
}

cv::Mat ImagePrefetcher::get(const ImageEntry &e) {
  const auto index = entry_index(images_, e);
  return index ? get(*index) : decode_entry(e);
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
  return decode(index);
}

} // namespace ovton::core
