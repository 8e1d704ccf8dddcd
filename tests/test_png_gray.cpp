// The fast gray-PNG decoder (ov_core/io/png_gray.cpp) against OpenCV's: the same pixels for every filter type and
// compression level, and a refusal (so that the caller falls back to cv::imread) for anything else or anything damaged.
#include "ov_core/io/png_gray.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#if __has_include(<libdeflate.h>)
#include <libdeflate.h>
#endif

#include <cstdlib>
#include <random>
#include <vector>

namespace {

/// A noisy, textured 8-bit image: noise keeps libpng's adaptive filter choice varied across rows.
cv::Mat test_image(int w, int h, unsigned seed) {
  cv::Mat img(h, w, CV_8UC1);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> noise(-6, 6);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(((x / 7 + y / 5) % 2 ? 180 : 60) + (x * y) % 37 + noise(rng));
  return img;
}

std::vector<uint8_t> encode(const cv::Mat &img, std::vector<int> params) {
  std::vector<uint8_t> buf;
  EXPECT_TRUE(cv::imencode(".png", img, buf, params));
  return buf;
}

bool same(const cv::Mat &a, const cv::Mat &b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

} // namespace

TEST(PngGray, SamePixelsAsOpenCVForEveryFilterAndLevel) {
  if (!ovton::core::png_gray_fast_path_available())
    GTEST_SKIP() << "built without libdeflate";
  const cv::Mat img = test_image(97, 61, 3);
  // Strategies change the filters libpng picks (default: adaptive, all five; RLE/Huffman-only: often None/Sub).
  for (int strategy : {cv::IMWRITE_PNG_STRATEGY_DEFAULT, cv::IMWRITE_PNG_STRATEGY_FILTERED,
                       cv::IMWRITE_PNG_STRATEGY_HUFFMAN_ONLY, cv::IMWRITE_PNG_STRATEGY_RLE})
    for (int level : {0, 1, 3, 9}) {
      const auto buf = encode(img, {cv::IMWRITE_PNG_COMPRESSION, level, cv::IMWRITE_PNG_STRATEGY, strategy});
      cv::Mat fast;
      ASSERT_TRUE(ovton::core::decode_png_gray8(buf.data(), buf.size(), fast)) << strategy << " " << level;
      EXPECT_TRUE(same(fast, cv::imdecode(buf, cv::IMREAD_GRAYSCALE))) << strategy << " " << level;
      EXPECT_TRUE(same(fast, img));
    }
}

#if __has_include(<libdeflate.h>)
namespace {

void put32(std::vector<uint8_t> &v, uint32_t x) {
  for (int s = 24; s >= 0; s -= 8)
    v.push_back(static_cast<uint8_t>(x >> s));
}

void chunk(std::vector<uint8_t> &png, const char *type, const std::vector<uint8_t> &body) {
  put32(png, static_cast<uint32_t>(body.size()));
  std::vector<uint8_t> tb(type, type + 4);
  tb.insert(tb.end(), body.begin(), body.end());
  png.insert(png.end(), tb.begin(), tb.end());
  put32(png, libdeflate_crc32(0, tb.data(), tb.size()));
}

/// A gray PNG whose row y is filtered with type filters[y % filters.size()] (the PNG specification's filters).
std::vector<uint8_t> png_with_filters(const cv::Mat &img, const std::vector<int> &filters) {
  const int w = img.cols, h = img.rows;
  std::vector<uint8_t> raw;
  for (int y = 0; y < h; ++y) {
    const int t = filters[static_cast<size_t>(y) % filters.size()];
    raw.push_back(static_cast<uint8_t>(t));
    for (int x = 0; x < w; ++x) {
      const int v = img.at<uint8_t>(y, x), a = x > 0 ? img.at<uint8_t>(y, x - 1) : 0,
                b = y > 0 ? img.at<uint8_t>(y - 1, x) : 0, c = x > 0 && y > 0 ? img.at<uint8_t>(y - 1, x - 1) : 0;
      const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
      const int paeth = pa <= pb && pa <= pc ? a : (pb <= pc ? b : c);
      const int pred[5] = {0, a, b, (a + b) / 2, paeth};
      raw.push_back(static_cast<uint8_t>(v - pred[t]));
    }
  }
  libdeflate_compressor *c = libdeflate_alloc_compressor(6);
  std::vector<uint8_t> z(libdeflate_zlib_compress_bound(c, raw.size()));
  z.resize(libdeflate_zlib_compress(c, raw.data(), raw.size(), z.data(), z.size()));
  libdeflate_free_compressor(c);
  std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'}, ihdr;
  put32(ihdr, static_cast<uint32_t>(w));
  put32(ihdr, static_cast<uint32_t>(h));
  ihdr.insert(ihdr.end(), {8, 0, 0, 0, 0});
  chunk(png, "IHDR", ihdr);
  chunk(png, "tEXt", {'a', 0, 'b'}); // an ancillary chunk to skip
  // Two IDAT chunks: the stream may be split anywhere.
  const size_t half = z.size() / 2;
  chunk(png, "IDAT", std::vector<uint8_t>(z.begin(), z.begin() + static_cast<long>(half)));
  chunk(png, "IDAT", std::vector<uint8_t>(z.begin() + static_cast<long>(half), z.end()));
  chunk(png, "IEND", {});
  return png;
}

} // namespace

TEST(PngGray, EveryRowFilterTypeDecodes) {
  // Average and Paeth rows are undone four at a time (png_gray.cpp). `all16` gives the groups of rows 4k..4k+3 every
  // mix of the two types; a group that meets another type, or the image's last rows, falls back to one row at a
  // time. Widths down to the smallest a group takes (4) and below it.
  std::vector<int> all16;
  for (int code = 0; code < 16; ++code)
    for (int j = 0; j < 4; ++j)
      all16.push_back((code >> j) & 1 ? 4 : 3);
  const std::vector<std::vector<int>> patterns{{0}, {1}, {2}, {3}, {4}, {4, 3, 2, 1, 0}, {3, 4, 4, 3, 4}, all16};
  for (const int w : {83, 5, 4, 3, 1})
    for (const std::vector<int> &filters : patterns) {
      const cv::Mat img = test_image(w, 66, 11);
      const auto png = png_with_filters(img, filters);
      // OpenCV (libpng) reads the hand-made file as the image: the encoder above is right.
      ASSERT_TRUE(same(cv::imdecode(png, cv::IMREAD_GRAYSCALE), img)) << filters[0] << " w " << w;
      cv::Mat fast;
      if (!ovton::core::png_gray_fast_path_available())
        continue;
      ASSERT_TRUE(ovton::core::decode_png_gray8(png.data(), png.size(), fast)) << filters[0] << " w " << w;
      EXPECT_TRUE(same(fast, img)) << "filters from " << filters[0] << ", " << filters.size() << " long, w " << w;
    }
}
#endif

TEST(PngGray, RefusesOtherKindsAndDamagedFiles) {
  if (!ovton::core::png_gray_fast_path_available())
    GTEST_SKIP() << "built without libdeflate";
  const cv::Mat img = test_image(50, 30, 7);
  cv::Mat out;
  // Colour, 16 bit: left to OpenCV.
  cv::Mat bgr;
  cv::cvtColor(img, bgr, cv::COLOR_GRAY2BGR);
  auto buf = encode(bgr, {});
  EXPECT_FALSE(ovton::core::decode_png_gray8(buf.data(), buf.size(), out));
  cv::Mat img16;
  img.convertTo(img16, CV_16U, 256);
  buf = encode(img16, {});
  EXPECT_FALSE(ovton::core::decode_png_gray8(buf.data(), buf.size(), out));

  const auto good = encode(img, {});
  ASSERT_TRUE(ovton::core::decode_png_gray8(good.data(), good.size(), out));
  // Truncated anywhere: refused, never a crash or a partial image.
  for (size_t n = 0; n < good.size(); n += 7)
    EXPECT_FALSE(ovton::core::decode_png_gray8(good.data(), n, out)) << n;
  // Any flipped byte after the signature: refused (CRC, Adler-32, header checks) or, in an ignored ancillary chunk,
  // decoded to the same pixels. Never a different image.
  for (size_t i = 8; i < good.size(); ++i) {
    auto bad = good;
    bad[i] ^= 0x5a;
    if (ovton::core::decode_png_gray8(bad.data(), bad.size(), out)) {
      EXPECT_TRUE(same(out, img)) << "byte " << i;
    }
  }
  EXPECT_FALSE(ovton::core::read_png_gray8("/nonexistent/ovton/none.png", out));
}
