#include "ov_core/io/image_io.h"
#include "ov_core/io/image_store.h"
#include "ov_core/types/errors.h"

#include <string>

namespace ovton::core {

void check_gray_image(const cv::Mat &img, const ImageEntry &e, int width, int height) {
  if (img.empty())
    throw DataError(e.path, "unreadable image (listed for stamp " + std::to_string(e.t_cam_ns) + ")");
  if (img.cols != width || img.rows != height)
    throw DataError(e.path, "image is " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                                " px, the camera calibration says " + std::to_string(width) + "x" +
                                std::to_string(height));
}

cv::Mat load_gray_image(const ImageEntry &e, int width, int height) {
  // Through the image store: a bag's images live in the bag, a folder's in PNG files.
  cv::Mat img = load_image(e);
  check_gray_image(img, e, width, height);
  return img;
}

} // namespace ovton::core
