#pragma once
// Decoding a dataset's images with the checks that name the file: an unreadable file or an image of another size than
// the calibration's would otherwise surface deep in the tracker as a usage error without the file's name.
#include "ov_core/types/sensor_data.h"

#include <opencv2/core.hpp>

namespace ovton::core {

/// Throws DataError naming e.path when `img` is empty (unreadable) or not width x height.
void check_gray_image(const cv::Mat &img, const ImageEntry &e, int width, int height);

/// Decodes e.path as 8-bit grayscale and checks it as above.
cv::Mat load_gray_image(const ImageEntry &e, int width, int height);

} // namespace ovton::core
