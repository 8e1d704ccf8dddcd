#pragma once
// OpenCV's image codecs, loaded on demand. libopencv_imgcodecs brings 140 shared libraries with it (GDAL, GDCM, codecs
// of every kind) and linking it cost every ovton process about 0.05 s of CPU at start (docs/peer.md, "Speed"), a tenth
// of a run on a short recording. ovton decodes the PNGs that every EuRoC and rendered folder holds itself
// (png_gray.h), so the codecs live in a small plugin next to the binary (plugins/imgcodecs_plugin.cpp,
// libovton_imgcodecs.so) that is opened the first time anything else is asked for: another image format, the
// simulator's PNG writer, a chart.
#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ovton::core {

/// 8-bit grayscale pixels of the image file `path`: 8-bit gray PNGs by the fast decoder, any other file as
/// cv::imread(IMREAD_GRAYSCALE) reads it. Empty when the file cannot be read or decoded (the caller names the file).
cv::Mat read_gray_image(const std::string &path);
/// 8-bit grayscale pixels of an image file held in memory (a ROS CompressedImage's JPEG or PNG): 8-bit gray PNGs by
/// the fast decoder, anything else as cv::imdecode(IMREAD_GRAYSCALE) reads it. Empty when it cannot be decoded.
cv::Mat decode_gray_image(const uint8_t *data, size_t size);
/// 8-bit BGR pixels of `path` as cv::imread(IMREAD_COLOR) reads them; empty when unreadable.
cv::Mat read_color_image(const std::string &path);
/// cv::imwrite: false when the file cannot be written.
bool write_image(const std::string &path, const cv::Mat &img, const std::vector<int> &params = {});
/// cv::imencode with extension `ext` (".png"): false when it cannot be encoded.
bool encode_image(const std::string &ext, const cv::Mat &img, std::vector<uchar> &bytes,
                  const std::vector<int> &params = {});
/// The PNG writer's zlib level (cv::IMWRITE_PNG_COMPRESSION) for write_image's params.
int png_compression_param();
/// The JPEG writer's quality (cv::IMWRITE_JPEG_QUALITY) for write_image's and encode_image's params.
int jpeg_quality_param();

} // namespace ovton::core
