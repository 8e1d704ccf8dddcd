#pragma once
// Where an image's pixels come from. A dataset folder lists PNG files (ImageEntry::path); a ROS bag holds the pixels in
// its messages, which are read one at a time when the replay reaches them, so that a bag of any size replays in flat
// memory. Every consumer (the filter's default loader, the prefetcher, `ovton export`) goes through load_image().
#include "ov_core/types/sensor_data.h"

#include <opencv2/core.hpp>

namespace ovton::core {

/// A container of images that are not files of their own (a ROS bag). Implementations must be safe to call from
/// several threads (the prefetcher decodes on its own thread; an index asked again is decoded on the caller's).
class ImageStore {
public:
  virtual ~ImageStore() = default;
  /// The 8-bit grayscale image of entry `e` (e.store_index says which). Throws DataError naming the container and the
  /// message when the pixels cannot be had (corrupt or truncated data, unsupported encoding).
  virtual cv::Mat load(const ImageEntry &e) const = 0;
};

/// 8-bit grayscale pixels of `e`: from its store, or read_gray_image of its path (empty when the file is unreadable:
/// the caller names the file). Feature-level entries have no pixels (empty).
cv::Mat load_image(const ImageEntry &e);

} // namespace ovton::core
