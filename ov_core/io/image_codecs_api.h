#pragma once
// The table of functions the image-codecs plugin (plugins/imgcodecs_plugin.cpp) hands to ov_core/io/image_codecs.cpp.
// Both sides are built from this tree with the same compiler and OpenCV, so the entries pass C++ types; `abi` guards
// against a plugin left over from another build of a different shape.
#include <opencv2/core.hpp>

#include <string>
#include <vector>

extern "C" {

struct OvtonImageCodecs {
  int abi;
  cv::Mat (*read)(const std::string &path, bool color);
  /// The image file held in `size` bytes at `data` (a ROS CompressedImage); empty when it cannot be decoded.
  cv::Mat (*decode)(const uchar *data, size_t size, bool color);
  bool (*write)(const std::string &path, const cv::Mat &img, const std::vector<int> &params);
  bool (*encode)(const std::string &ext, const cv::Mat &img, const std::vector<int> &params, std::vector<uchar> &bytes);
  int png_compression;
  int jpeg_quality; ///< cv::IMWRITE_JPEG_QUALITY
};

/// The plugin's one exported symbol.
const OvtonImageCodecs *ovton_image_codecs();

} // extern "C"

inline constexpr int kOvtonImageCodecsAbi = 2;
inline constexpr const char *kOvtonImageCodecsSymbol = "ovton_image_codecs";
