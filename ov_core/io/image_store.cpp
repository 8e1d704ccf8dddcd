#include "ov_core/io/image_store.h"
#include "ov_core/io/png_gray.h"

#include <opencv2/imgcodecs.hpp>

namespace ov_core {

cv::Mat load_image(const ImageEntry &e) {
  if (e.store)
    return e.store->load(e);
  if (e.features)
    return cv::Mat();
  // 8-bit gray PNGs (every EuRoC folder) through the fast decoder; any other file as OpenCV reads it.
  cv::Mat img;
  if (read_png_gray8(e.path, img))
    return img;
  return cv::imread(e.path, cv::IMREAD_GRAYSCALE);
}

} // namespace ov_core
