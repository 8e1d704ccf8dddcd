#include "ov_core/io/image_message.h"
#include "ov_core/io/image_codecs.h"
#include "ov_core/types/errors.h"

#include <opencv2/imgproc.hpp>

#include <cstring>

namespace ovton::core {

namespace {

struct Encoding {
  const char *name;
  int channels;
  int bytes_per_channel;
  int to_gray; ///< cv::cvtColor code, -1 for none
};

constexpr Encoding kEncodings[] = {
    {"mono8", 1, 1, -1},
    {"8UC1", 1, 1, -1},
    {"mono16", 1, 2, -1},
    {"16UC1", 1, 2, -1},
    {"bgr8", 3, 1, cv::COLOR_BGR2GRAY},
    {"rgb8", 3, 1, cv::COLOR_RGB2GRAY},
    {"bgra8", 4, 1, cv::COLOR_BGRA2GRAY},
    {"rgba8", 4, 1, cv::COLOR_RGBA2GRAY},
};

const Encoding *find_encoding(const std::string &name) {
  for (const auto &e : kEncodings)
    if (name == e.name)
      return &e;
  return nullptr;
}

bool starts_with(const uint8_t *data, size_t size, const char *sig, size_t n) {
  return size >= n && std::memcmp(data, sig, n) == 0;
}
const char kPngSignature[] = "\x89PNG\r\n\x1a\n";

uint32_t be16(const uint8_t *p) {
  return static_cast<uint32_t>(p[0]) << 8 | p[1];
}
uint32_t be32(const uint8_t *p) {
  return be16(p) << 16 | be16(p + 2);
}

std::string size_text(int w, int h) {
  return std::to_string(w) + "x" + std::to_string(h);
}

} // namespace

void check_raw_image(const RawImageView &m, int width, int height, const std::string &file, const std::string &where) {
  const Encoding *enc = find_encoding(m.encoding);
  if (!enc)
    throw DataError(file, where + ": unsupported image encoding '" + m.encoding +
                              "' (supported: mono8, mono16, bgr8, rgb8, bgra8, rgba8)");
  if (static_cast<int>(m.width) != width || static_cast<int>(m.height) != height)
    throw DataError(file, where + ": image is " + size_text(m.width, m.height) + " px, the camera calibration says " +
                              size_text(width, height));
  const uint64_t row = static_cast<uint64_t>(m.width) * enc->channels * enc->bytes_per_channel;
  if (m.step < row || static_cast<uint64_t>(m.step) * m.height != m.size)
    throw DataError(file, where + ": " + std::to_string(m.size) + " bytes of pixels do not fit " +
                              size_text(m.width, m.height) + " " + m.encoding + " with a row step of " +
                              std::to_string(m.step));
}

cv::Mat raw_image_to_gray(const RawImageView &m, const std::string &file, const std::string &where) {
  check_raw_image(m, static_cast<int>(m.width), static_cast<int>(m.height), file, where);
  if (!m.data)
    throw DataError(file, where + ": the image's pixels were not read");
  const Encoding *enc = find_encoding(m.encoding);
  const int type = CV_MAKETYPE(enc->bytes_per_channel == 1 ? CV_8U : CV_16U, enc->channels);
  // A view of the message's bytes (rows may be padded: step), copied out by the conversions below.
  const cv::Mat view(static_cast<int>(m.height), static_cast<int>(m.width), type, const_cast<uint8_t *>(m.data),
                     m.step);
  cv::Mat gray;
  if (enc->bytes_per_channel == 2) {
    // The high byte: mono8 images widened to mono16 (v << 8, or v * 257 for the full range) come back as the same
    // mono8 pixels, so both recordings give the same run; a rounding scale (1/256) would move every v >= 128 of
    // v * 257 up by one. Read byte by byte: the high byte's place is the message's endianness, whatever the host's, and
    // a message's pixels need not be 2-byte aligned.
    const int high = m.big_endian ? 0 : 1;
    gray.create(view.rows, view.cols, CV_8UC1);
    for (int r = 0; r < view.rows; ++r) {
      const uint8_t *p = view.ptr<uint8_t>(r);
      auto *q = gray.ptr<uint8_t>(r);
      for (int c = 0; c < view.cols; ++c)
        q[c] = p[2 * c + high];
    }
  } else if (enc->to_gray >= 0) {
    cv::cvtColor(view, gray, enc->to_gray);
  } else {
    gray = view.clone();
  }
  return gray;
}

CompressedFormat compressed_format(const std::string &format, const uint8_t *data, size_t size, const std::string &file,
                                   const std::string &where) {
  // compressedDepth (image_transport's depth plugin) is a PNG behind a depth-quantisation header, not an image.
  if (format.find("compressedDepth") != std::string::npos)
    throw DataError(file, where + ": CompressedImage format '" + format + "' is a depth image, not a camera image");
  const bool jpeg = format.find("jpeg") != std::string::npos || format.find("jpg") != std::string::npos;
  const bool png = format.find("png") != std::string::npos;
  if (jpeg != png)
    return jpeg ? CompressedFormat::Jpeg : CompressedFormat::Png;
  if (starts_with(data, size, "\xff\xd8\xff", 3))
    return CompressedFormat::Jpeg;
  if (starts_with(data, size, kPngSignature, 8))
    return CompressedFormat::Png;
  throw DataError(file, where + ": unsupported CompressedImage format '" + format + "' (supported: jpeg, png)");
}

std::optional<cv::Size> compressed_image_size(const uint8_t *data, size_t size) {
  if (starts_with(data, size, kPngSignature, 8)) {
    // The IHDR chunk comes first: length, "IHDR", width, height (big-endian).
    if (size < 24 || std::memcmp(data + 12, "IHDR", 4) != 0)
      return std::nullopt;
    return cv::Size(static_cast<int>(be32(data + 16)), static_cast<int>(be32(data + 20)));
  }
  if (!starts_with(data, size, "\xff\xd8", 2))
    return std::nullopt;
  // JPEG: walk the marker segments up to the frame header (SOFn) and read its height and width.
  size_t at = 2;
  while (at + 4 <= size) {
    if (data[at] != 0xff)
      return std::nullopt;
    const uint8_t marker = data[at + 1];
    if (marker == 0xff) { // fill byte
      ++at;
      continue;
    }
    const size_t len = be16(data + at + 2);
    const bool sof = marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc;
    if (sof) {
      if (at + 9 > size || len < 7)
        return std::nullopt;
      return cv::Size(static_cast<int>(be16(data + at + 7)), static_cast<int>(be16(data + at + 5)));
    }
    if (marker == 0xda || len < 2) // start of scan before any frame header
      return std::nullopt;
    at += 2 + len;
  }
  return std::nullopt;
}

void check_compressed_image(const std::string &format, const uint8_t *data, size_t size, int width, int height,
                            const std::string &file, const std::string &where) {
  const CompressedFormat f = compressed_format(format, data, size, file, where);
  const auto s = compressed_image_size(data, size);
  if (!s)
    throw DataError(file, where + ": the CompressedImage's " + (f == CompressedFormat::Jpeg ? "JPEG" : "PNG") +
                              " header is unreadable (format '" + format + "', " + std::to_string(size) + " bytes)");
  if (s->width != width || s->height != height)
    throw DataError(file, where + ": image is " + size_text(s->width, s->height) + " px, the camera calibration says " +
                              size_text(width, height));
}

cv::Mat compressed_to_gray(const std::string &format, const uint8_t *data, size_t size, const std::string &file,
                           const std::string &where) {
  const CompressedFormat f = compressed_format(format, data, size, file, where);
  cv::Mat gray = decode_gray_image(data, size);
  if (gray.empty())
    throw DataError(file, where + ": the CompressedImage's " + (f == CompressedFormat::Jpeg ? "JPEG" : "PNG") +
                              " data cannot be decoded (" + std::to_string(size) + " bytes)");
  return gray;
}

} // namespace ovton::core
