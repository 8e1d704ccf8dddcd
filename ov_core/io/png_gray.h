#pragma once
// A fast path for the one PNG kind every EuRoC and rendered folder holds: 8-bit grayscale, not interlaced. The zlib
// stream is inflated in one call by libdeflate (about twice zlib's speed) and the rows are unfiltered here; anything
// else (colour, 16 bit, palette, transparency, interlace, a damaged file) is left to cv::imread by the caller.
#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace ovton::core {

/// True when this build has the fast path (libdeflate found at configure time).
bool png_gray_fast_path_available();

/// Decodes a PNG file's bytes into `out` (CV_8UC1) when it is 8-bit grayscale, non-interlaced and intact (chunk
/// CRCs, zlib's Adler-32 and the exact pixel count are checked); returns false otherwise, `out` then undefined.
bool decode_png_gray8(const uint8_t *data, size_t size, cv::Mat &out);

/// Reads `path` and decodes it as above; false when the file cannot be read or is not of that kind.
bool read_png_gray8(const std::string &path, cv::Mat &out);

} // namespace ovton::core
