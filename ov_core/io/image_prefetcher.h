#pragma once
// Decodes a dataset's images on a second thread, in replay order, a few ahead of the consumer: PNG decoding is about a
// third of a frame's cost (docs/benchmarks.md), and on a 2-core machine it can overlap the filter's work.
#include "ov_core/types/sensor_data.h"

#include <condition_variable>
#include <cstddef>
#include <exception>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <thread>
#include <vector>

namespace ovton::core {

/// Images decoded before the replay (the coarse t_d search's window), by index into the dataset's list. Shared
/// read-only: a cv::Mat handed out shares the pixels, which no consumer writes.
using DecodedImages = std::map<size_t, cv::Mat>;

class ImagePrefetcher {
public:
  /// Starts decoding images[0], images[1], ... (grayscale) with at most `ahead` decoded images waiting. Feature-level
  /// entries (features set) are not decoded, nor those in `given`, which are handed out as they are. `images` must
  /// outlive the prefetcher.
  explicit ImagePrefetcher(const std::vector<ImageEntry> &images, size_t ahead = 2,
                           std::shared_ptr<const DecodedImages> given = nullptr);
  ~ImagePrefetcher();
  ImagePrefetcher(const ImagePrefetcher &) = delete;
  ImagePrefetcher &operator=(const ImagePrefetcher &) = delete;

  /// The decoded image of images[index] (empty if the file is unreadable: the caller reports it, as without the
  /// prefetcher; an error the image's store threw is rethrown here). Indices normally increase between calls; skipped
  /// ones are dropped, and an index asked again or already dropped is decoded here instead. An index outside the list
  /// gives an empty image.
  cv::Mat get(size_t index);
  /// The same for an entry of the list (the replay hands out the list's own entries); any other entry is decoded here.
  cv::Mat get(const ImageEntry &e);

  /// One decoded image, or what decoding it threw (rethrown by get()).
  struct Decoded {
    cv::Mat image;
    std::exception_ptr error;
  };

private:
  void work();
  /// images[index] from `given_`, else decoded.
  cv::Mat decode(size_t index) const;
  Decoded decode_caught(size_t index) const;

  const std::vector<ImageEntry> &images_;
  const size_t ahead_;
  const std::shared_ptr<const DecodedImages> given_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::map<size_t, Decoded> ready_;                       ///< decoded, not yet taken (indices ≥ wanted_)
  size_t wanted_ = 0;                                     ///< lowest index the consumer may still ask for
  size_t produced_ = 0;                                   ///< next index the thread decodes
  size_t in_flight_ = std::numeric_limits<size_t>::max(); ///< index being decoded now
  bool stop_ = false;
  std::thread thread_; ///< last: started once everything above is constructed
};

} // namespace ovton::core
