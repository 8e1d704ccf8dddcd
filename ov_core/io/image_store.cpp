#include "ov_core/io/image_store.h"
#include "ov_core/io/image_codecs.h"

namespace ovton::core {

cv::Mat load_image(const ImageEntry &e) {
  if (e.store)
    return e.store->load(e);
  if (e.features)
    return cv::Mat();
  return read_gray_image(e.path);
}

} // namespace ovton::core
