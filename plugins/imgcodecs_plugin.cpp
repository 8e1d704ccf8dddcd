// libovton_imgcodecs.so: OpenCV's image codecs behind the table of ov_core/io/image_codecs_api.h, so that the ovton
// binary itself does not link libopencv_imgcodecs (ov_core/io/image_codecs.h says why).
#include "ov_core/io/image_codecs_api.h"

#include <opencv2/imgcodecs.hpp>

#include <cstdint>

namespace {

cv::Mat read(const std::string &path, bool color) {
  return cv::imread(path, color ? cv::IMREAD_COLOR : cv::IMREAD_GRAYSCALE);
}

cv::Mat decode(const uchar *data, size_t size, bool color) {
  if (size == 0 || size > static_cast<size_t>(INT32_MAX))
    return cv::Mat();
  // A header over the caller's bytes: imdecode reads them in place.
  const cv::Mat bytes(1, static_cast<int>(size), CV_8UC1, const_cast<uchar *>(data));
  return cv::imdecode(bytes, color ? cv::IMREAD_COLOR : cv::IMREAD_GRAYSCALE);
}

bool write(const std::string &path, const cv::Mat &img, const std::vector<int> &params) {
  return cv::imwrite(path, img, params);
}

bool encode(const std::string &ext, const cv::Mat &img, const std::vector<int> &params, std::vector<uchar> &bytes) {
  return cv::imencode(ext, img, bytes, params);
}

const OvtonImageCodecs kTable{kOvtonImageCodecsAbi,    read, decode, write, encode, cv::IMWRITE_PNG_COMPRESSION,
                              cv::IMWRITE_JPEG_QUALITY};

} // namespace

extern "C" __attribute__((visibility("default"))) const OvtonImageCodecs *ovton_image_codecs() {
  return &kTable;
}
