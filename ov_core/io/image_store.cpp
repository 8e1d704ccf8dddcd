#include "ov_core/io/image_store.h"

#include <opencv2/imgcodecs.hpp>

namespace ov_core {

cv::Mat load_image(const ImageEntry &e) {
  if (e.store)
    return e.store->load(e);
  return e.features ? cv::Mat() : cv::imread(e.path, cv::IMREAD_GRAYSCALE);
}

} // namespace ov_core
