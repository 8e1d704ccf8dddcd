#include "ov_core/io/png_gray.h"

#include <array>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <utility>

#ifdef OVTON_HAVE_LIBDEFLATE
#include <libdeflate.h>
#endif

namespace ovton::core {

#ifdef OVTON_HAVE_LIBDEFLATE

namespace {

uint32_t be32(const uint8_t *p) {
  return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | uint32_t(p[3]);
}

struct DecompressorDeleter {
  void operator()(libdeflate_decompressor *d) const { libdeflate_free_decompressor(d); }
};

/// One decompressor and one set of buffers per thread (the prefetcher decodes on its own thread).
struct Scratch {
  std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> dec{libdeflate_alloc_decompressor()};
  std::vector<uint8_t> file, idat, raw;
};

Scratch &scratch() {
  thread_local Scratch s;
  return s;
}

/// One pixel of an Average (Paeth = false) or Paeth row: `a` the pixel to the left, `c` the one above that.
template <bool Paeth>
inline void unfilter_pixel(const uint8_t *in, const uint8_t *above, uint8_t *out, size_t i, int &a, int &c) {
  const int b = above[i];
  int pred;
  if constexpr (Paeth) {
    // Branch-free: the predictor's choice is data-dependent and unpredictable, and each pixel waits for the one
    // before it, so a mispredicted branch costs the whole row's chain. Same choices as the specification's
    // (ties to a, then b): c only when it is strictly closest.
    const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
    const int m = pa <= pb ? pa : pb;
    pred = pa <= pb ? a : b;
    pred = pc < m ? c : pred;
  } else {
    pred = (a + b) >> 1;
  }
  a = static_cast<uint8_t>(in[i] + pred);
  out[i] = static_cast<uint8_t>(a);
  c = b;
}

/// Undoes the PNG row filters for one byte per pixel; `prev` is the previous unfiltered row (zeros for the first).
bool unfilter_row(int type, const uint8_t *in, const uint8_t *prev, uint8_t *out, int w) {
  switch (type) {
  case 0:
    std::memcpy(out, in, static_cast<size_t>(w));
    return true;
  case 1: {
    uint8_t a = 0;
    for (int i = 0; i < w; ++i)
      out[i] = a = static_cast<uint8_t>(in[i] + a);
    return true;
  }
  case 2:
    for (int i = 0; i < w; ++i)
      out[i] = static_cast<uint8_t>(in[i] + prev[i]);
    return true;
  case 3: {
    int a = 0, c = 0;
    for (size_t i = 0; i < static_cast<size_t>(w); ++i)
      unfilter_pixel<false>(in, prev, out, i, a, c);
    return true;
  }
  case 4: {
    int a = 0, c = 0;
    for (size_t i = 0; i < static_cast<size_t>(w); ++i)
      unfilter_pixel<true>(in, prev, out, i, a, c);
    return true;
  }
  default:
    return false;
  }
}

/// Four consecutive Average/Paeth rows at once, each one pixel behind the row above it, which it needs up to its own
/// column. Within a row every pixel waits for the one to its left (a chain of about seven cycles for Paeth); four
/// independent chains keep the core busy instead of waiting. `in` and `in_stride` the filtered rows (after their
/// filter-type byte), `above` the unfiltered row over the first, `out` and `out_stride` four output rows of `w`
/// (w >= 4) bytes.
template <bool P0, bool P1, bool P2, bool P3>
void unfilter_four_rows(const uint8_t *in, size_t in_stride, const uint8_t *above, uint8_t *out, size_t out_stride,
                        size_t w) {
  const uint8_t *i0 = in, *i1 = in + in_stride, *i2 = in + 2 * in_stride, *i3 = in + 3 * in_stride;
  uint8_t *o0 = out, *o1 = out + out_stride, *o2 = out + 2 * out_stride, *o3 = out + 3 * out_stride;
  int a0 = 0, a1 = 0, a2 = 0, a3 = 0, c0 = 0, c1 = 0, c2 = 0, c3 = 0;
  unfilter_pixel<P0>(i0, above, o0, 0, a0, c0);
  unfilter_pixel<P0>(i0, above, o0, 1, a0, c0);
  unfilter_pixel<P1>(i1, o0, o1, 0, a1, c1);
  unfilter_pixel<P0>(i0, above, o0, 2, a0, c0);
  unfilter_pixel<P1>(i1, o0, o1, 1, a1, c1);
  unfilter_pixel<P2>(i2, o1, o2, 0, a2, c2);
  for (size_t t = 3; t < w; ++t) {
    unfilter_pixel<P0>(i0, above, o0, t, a0, c0);
    unfilter_pixel<P1>(i1, o0, o1, t - 1, a1, c1);
    unfilter_pixel<P2>(i2, o1, o2, t - 2, a2, c2);
    unfilter_pixel<P3>(i3, o2, o3, t - 3, a3, c3);
  }
  unfilter_pixel<P1>(i1, o0, o1, w - 1, a1, c1);
  unfilter_pixel<P2>(i2, o1, o2, w - 2, a2, c2);
  unfilter_pixel<P3>(i3, o2, o3, w - 3, a3, c3);
  unfilter_pixel<P2>(i2, o1, o2, w - 1, a2, c2);
  unfilter_pixel<P3>(i3, o2, o3, w - 2, a3, c3);
  unfilter_pixel<P3>(i3, o2, o3, w - 1, a3, c3);
}

using FourRows = void (*)(const uint8_t *, size_t, const uint8_t *, uint8_t *, size_t, size_t);

/// The kernel for four rows' types (bit j set: row j is Paeth, clear: Average).
template <size_t... K> constexpr std::array<FourRows, 16> four_row_kernels(std::index_sequence<K...>) {
  return {&unfilter_four_rows<(K & 1) != 0, (K & 2) != 0, (K & 4) != 0, (K & 8) != 0>...};
}
constexpr std::array<FourRows, 16> kFourRows = four_row_kernels(std::make_index_sequence<16>{});

} // namespace

bool png_gray_fast_path_available() {
  return true;
}

bool decode_png_gray8(const uint8_t *data, size_t size, cv::Mat &out) {
  static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (size < 8 + 25 || std::memcmp(data, kSignature, 8) != 0)
    return false;
  Scratch &s = scratch();
  if (!s.dec)
    return false;
  s.idat.clear();
  int w = 0, h = 0;
  bool have_header = false, have_end = false;
  size_t pos = 8;
  while (pos + 12 <= size) {
    const uint32_t len = be32(data + pos);
    if (len > size - pos - 12)
      return false;
    const uint8_t *type = data + pos + 4, *body = data + pos + 8;
    const bool critical = !(type[0] & 0x20);
    // Critical chunks must be intact, as libpng requires; ancillary ones are ignored without a look.
    if (critical && libdeflate_crc32(0, type, len + 4) != be32(body + len))
      return false;
    if (std::memcmp(type, "IHDR", 4) == 0) {
      if (have_header || len != 13)
        return false;
      const uint32_t uw = be32(body), uh = be32(body + 4);
      // bit depth 8, colour type 0 (gray), compression 0, filter 0, interlace 0
      if (uw == 0 || uh == 0 || uw > 65535 || uh > 65535 || body[8] != 8 || body[9] != 0 || body[10] != 0 ||
          body[11] != 0 || body[12] != 0)
        return false;
      w = static_cast<int>(uw);
      h = static_cast<int>(uh);
      have_header = true;
    } else if (!have_header) {
      return false; // IHDR must come first
    } else if (std::memcmp(type, "IDAT", 4) == 0) {
      s.idat.insert(s.idat.end(), body, body + len);
    } else if (std::memcmp(type, "tRNS", 4) == 0) {
      return false; // transparency: cv::imread decides what it means
    } else if (std::memcmp(type, "IEND", 4) == 0) {
      have_end = true;
      break;
    } else if (critical) {
      return false; // PLTE in a gray image, or a critical chunk this decoder does not know
    }
    pos += 12 + static_cast<size_t>(len);
  }
  if (!have_header || !have_end || s.idat.empty())
    return false;
  const size_t stride = static_cast<size_t>(w) + 1;
  s.raw.resize(stride * static_cast<size_t>(h));
  // Exactly one filter byte and w pixels per row, nothing more or less (a null actual size asks for that).
  if (libdeflate_zlib_decompress(s.dec.get(), s.idat.data(), s.idat.size(), s.raw.data(), s.raw.size(), nullptr) !=
      LIBDEFLATE_SUCCESS)
    return false;
  out.create(h, w, CV_8UC1);
  std::vector<uint8_t> zeros;
  for (int y = 0; y < h;) {
    const uint8_t *in = s.raw.data() + static_cast<size_t>(y) * stride;
    const uint8_t *prev = nullptr;
    if (y > 0) {
      prev = out.ptr<uint8_t>(y - 1);
    } else {
      zeros.assign(static_cast<size_t>(w), 0);
      prev = zeros.data();
    }
    // Average and Paeth rows (nearly all of them in EuRoC's and the renders' files) four at a time.
    int code = 0;
    bool four = y + 4 <= h && w >= 4;
    for (int j = 0; four && j < 4; ++j) {
      const uint8_t type = in[static_cast<size_t>(j) * stride];
      four = type == 3 || type == 4;
      code |= (type == 4) << j;
    }
    if (four) {
      kFourRows[static_cast<size_t>(code)](in + 1, stride, prev, out.ptr<uint8_t>(y), out.step[0],
                                           static_cast<size_t>(w));
      y += 4;
      continue;
    }
    if (!unfilter_row(in[0], in + 1, prev, out.ptr<uint8_t>(y), w))
      return false;
    ++y;
  }
  return true;
}

bool read_png_gray8(const std::string &path, cv::Mat &out) {
  std::FILE *f = std::fopen(path.c_str(), "rb");
  if (!f)
    return false;
  // The chunk walk and inflate use the thread's other buffers, so the file's bytes can stay in s.file.
  Scratch &s = scratch();
  bool ok = std::fseek(f, 0, SEEK_END) == 0;
  const long n = ok ? std::ftell(f) : -1;
  ok = ok && n > 0 && std::fseek(f, 0, SEEK_SET) == 0;
  if (ok) {
    s.file.resize(static_cast<size_t>(n));
    ok = std::fread(s.file.data(), 1, s.file.size(), f) == s.file.size();
  }
  std::fclose(f);
  ok = ok && decode_png_gray8(s.file.data(), s.file.size(), out);
  return ok;
}

#else

bool png_gray_fast_path_available() {
  return false;
}
bool decode_png_gray8(const uint8_t *, size_t, cv::Mat &) {
  return false;
}
bool read_png_gray8(const std::string &, cv::Mat &) {
  return false;
}

#endif

} // namespace ovton::core
