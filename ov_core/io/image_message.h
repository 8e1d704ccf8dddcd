#pragma once
// The pixels of an image message as ROS 1 and ROS 2 carry them (sensor_msgs Image: raw pixels in a named encoding;
// sensor_msgs CompressedImage: a JPEG or PNG file), checked and converted to 8-bit gray in one place for every reader.
// Checks name the container (file) and the message (where).
#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace ovton::core {

/// A raw sensor_msgs Image, as a view of the message's bytes. `data` may be null when only the message's first bytes
/// were read (a reader checking an image at load): `size` is then what the message declares.
struct RawImageView {
  uint32_t width = 0, height = 0, step = 0;
  std::string encoding;
  bool big_endian = false;
  const uint8_t *data = nullptr;
  size_t size = 0;
};

/// Throws DataError(file, where + ...) unless the image is one ovton can read (encoding mono8, mono16, bgr8, rgb8,
/// bgra8 or rgba8, also as 8UC1/16UC1; pixel bytes consistent with step and height) of width x height.
void check_raw_image(const RawImageView &m, int width, int height, const std::string &file, const std::string &where);
/// 8-bit grayscale pixels of a raw image (colour by OpenCV's luma weights, mono16 by its upper 8 bits).
cv::Mat raw_image_to_gray(const RawImageView &m, const std::string &file, const std::string &where);

/// The formats of sensor_msgs CompressedImage that ovton decodes.
enum class CompressedFormat { Jpeg, Png };

/// The format of a CompressedImage from its `format` field (image_transport writes "jpeg", "png" or
/// "bgr8; jpeg compressed bgr8"), or from the bytes' signature when the field names neither. Throws DataError for
/// anything else (compressedDepth, a format ovton cannot decode).
CompressedFormat compressed_format(const std::string &format, const uint8_t *data, size_t size, const std::string &file,
                                   const std::string &where);
/// Width x height from a JPEG's or PNG's header, without decoding the pixels; nothing when the header is not there.
std::optional<cv::Size> compressed_image_size(const uint8_t *data, size_t size);
/// Throws DataError unless the compressed image's header says width x height.
void check_compressed_image(const std::string &format, const uint8_t *data, size_t size, int width, int height,
                            const std::string &file, const std::string &where);
/// 8-bit grayscale pixels of a compressed image; throws DataError when it cannot be decoded.
cv::Mat compressed_to_gray(const std::string &format, const uint8_t *data, size_t size, const std::string &file,
                           const std::string &where);

} // namespace ovton::core
