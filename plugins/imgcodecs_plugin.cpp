// libovton_imgcodecs.so: OpenCV's image codecs behind the table of ov_core/io/image_codecs_api.h, so that the ovton
// binary itself does not link libopencv_imgcodecs (ov_core/io/image_codecs.h says why).
#include "ov_core/io/image_codecs_api.h"

#include <opencv2/imgcodecs.hpp>

namespace {

cv::Mat read(const std::string &path, bool color) {
  return cv::imread(path, color ? cv::IMREAD_COLOR : cv::IMREAD_GRAYSCALE);
}

bool write(const std::string &path, const cv::Mat &img, const std::vector<int> &params) {
  return cv::imwrite(path, img, params);
}

bool encode(const std::string &ext, const cv::Mat &img, const std::vector<int> &params, std::vector<uchar> &bytes) {
  return cv::imencode(ext, img, bytes, params);
}

const OvtonImageCodecs kTable{kOvtonImageCodecsAbi, read, write, encode, cv::IMWRITE_PNG_COMPRESSION};

} // namespace

extern "C" __attribute__((visibility("default"))) const OvtonImageCodecs *ovton_image_codecs() {
  return &kTable;
}
