#include "ov_core/io/mcap_format.h"
#include "ov_core/types/errors.h"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <memory>

namespace ovton::core::mcap {

namespace {

template <typename T> T get_le(const uint8_t *p) {
  T v = 0;
  for (size_t i = 0; i < sizeof(T); ++i)
    v |= static_cast<T>(static_cast<T>(p[i]) << (8 * i));
  return v;
}

template <typename T> void put_le(std::vector<uint8_t> &b, T v) {
  for (size_t i = 0; i < sizeof(T); ++i)
    b.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

/// The first room for a decoder's output: what `out` already holds (its memory is reused from chunk to chunk), at least
/// a few times the input, never past `limit`.
void start_output(std::vector<uint8_t> &out, uint64_t limit, size_t n) {
  out.resize(static_cast<size_t>(std::min<uint64_t>(limit, std::max<uint64_t>(out.capacity(), n * 4 + 4096))));
}

/// Grows `out` towards `limit` as a streaming decoder asks for room: a size field that lies costs nothing.
void grow(std::vector<uint8_t> &out, size_t used, uint64_t limit) {
  const size_t want = std::max<size_t>(used + (1u << 20), out.size() * 2);
  out.resize(static_cast<size_t>(std::min<uint64_t>(want, limit)));
}

void zstd_decompress(const uint8_t *src, size_t n, uint64_t size, std::vector<uint8_t> &out, const std::string &file,
                     const std::string &where) {
  const auto fail = [&](const std::string &what) {
    throw DataError(file, where + ": zstd data " + what + ": the chunk is corrupt");
  };
  const unsigned long long declared = ZSTD_getFrameContentSize(src, n);
  if (declared == ZSTD_CONTENTSIZE_ERROR)
    fail("has no valid frame header");
  if (declared != ZSTD_CONTENTSIZE_UNKNOWN && declared != size)
    fail("holds " + std::to_string(declared) + " bytes, the chunk says " + std::to_string(size));
  std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx *)> ctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
  // One byte more than declared is room enough to see that the data holds more.
  const uint64_t limit = size + 1;
  start_output(out, limit, n);
  ZSTD_inBuffer in{src, n, 0};
  size_t used = 0;
  while (used < limit) {
    if (used == out.size())
      grow(out, used, limit);
    ZSTD_outBuffer o{out.data(), out.size(), used};
    const size_t r = ZSTD_decompressStream(ctx.get(), &o, &in);
    if (ZSTD_isError(r))
      fail(std::string("cannot be decompressed (") + ZSTD_getErrorName(r) + ")");
    const bool progress = o.pos > used;
    used = o.pos;
    if (r == 0 && in.pos == in.size)
      break;
    if (in.pos == in.size && !progress)
      fail("ends inside a frame");
  }
  if (used != size || in.pos != in.size)
    fail("decompresses to " + std::to_string(used) + (used > size ? "+" : "") + " bytes, the chunk says " +
         std::to_string(size));
  out.resize(used);
}

void lz4_decompress(const uint8_t *src, size_t n, uint64_t size, std::vector<uint8_t> &out, const std::string &file,
                    const std::string &where) {
  const auto fail = [&](const std::string &what) {
    throw DataError(file, where + ": lz4 data " + what + ": the chunk is corrupt");
  };
  LZ4F_dctx *raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION)))
    throw std::bad_alloc();
  std::unique_ptr<LZ4F_dctx, size_t (*)(LZ4F_dctx *)> ctx(raw, LZ4F_freeDecompressionContext);
  const uint64_t limit = size + 1;
  start_output(out, limit, n);
  size_t used = 0, read = 0;
  while (used < limit) {
    if (used == out.size())
      grow(out, used, limit);
    size_t out_n = out.size() - used, in_n = n - read;
    const size_t r = LZ4F_decompress(ctx.get(), out.data() + used, &out_n, src + read, &in_n, nullptr);
    if (LZ4F_isError(r))
      fail(std::string("cannot be decompressed (") + LZ4F_getErrorName(r) + ")");
    used += out_n;
    read += in_n;
    if (r == 0 && read == n) // the last frame is complete
      break;
    if (read == n && out_n == 0 && in_n == 0)
      fail("ends inside a frame");
  }
  if (used != size || read != n)
    fail("decompresses to " + std::to_string(used) + (used > size ? "+" : "") + " bytes, the chunk says " +
         std::to_string(size));
  out.resize(used);
}

} // namespace

void FieldReader::fail(const std::string &what) const {
  throw DataError(file_, where_ + ": " + what);
}

const uint8_t *FieldReader::bytes(size_t n, const char *field) {
  if (n > size_ - pos_)
    fail(std::string("record ends before its field ") + field + " (" + std::to_string(n) + " bytes at byte " +
         std::to_string(pos_) + " of " + std::to_string(size_) + ")");
  const uint8_t *p = data_ + pos_;
  pos_ += n;
  return p;
}

uint8_t FieldReader::u8(const char *field) {
  return *bytes(1, field);
}
uint16_t FieldReader::u16(const char *field) {
  return get_le<uint16_t>(bytes(2, field));
}
uint32_t FieldReader::u32(const char *field) {
  return get_le<uint32_t>(bytes(4, field));
}
uint64_t FieldReader::u64(const char *field) {
  return get_le<uint64_t>(bytes(8, field));
}

std::string FieldReader::string(const char *field) {
  const uint32_t n = u32(field);
  const uint8_t *p = bytes(n, field);
  return std::string(reinterpret_cast<const char *>(p), n);
}

std::pair<const uint8_t *, size_t> FieldReader::prefixed(const char *field) {
  const uint32_t n = u32(field);
  return {bytes(n, field), n};
}

void put_u8(std::vector<uint8_t> &b, uint8_t v) {
  b.push_back(v);
}
void put_u16(std::vector<uint8_t> &b, uint16_t v) {
  put_le(b, v);
}
void put_u32(std::vector<uint8_t> &b, uint32_t v) {
  put_le(b, v);
}
void put_u64(std::vector<uint8_t> &b, uint64_t v) {
  put_le(b, v);
}
void put_string(std::vector<uint8_t> &b, const std::string &s) {
  put_u32(b, static_cast<uint32_t>(s.size()));
  b.insert(b.end(), s.begin(), s.end());
}
uint64_t get_u64(const uint8_t *p) {
  return get_le<uint64_t>(p);
}

uint32_t crc32(uint32_t crc, const uint8_t *data, size_t n) {
  // zlib takes uInt lengths: feed it in pieces below 4 GiB.
  while (n > 0) {
    const size_t piece = std::min<size_t>(n, 1u << 30);
    crc = static_cast<uint32_t>(::crc32(crc, data, static_cast<uInt>(piece)));
    data += piece;
    n -= piece;
  }
  return crc;
}

bool compression_supported(const std::string &name) {
  return name.empty() || name == "zstd" || name == "lz4";
}

void decompress_into(const std::string &compression, const uint8_t *src, size_t n, uint64_t uncompressed_size,
                     std::vector<uint8_t> &out, const std::string &file, const std::string &where) {
  if (uncompressed_size >= (uint64_t{1} << 40))
    throw DataError(file, where + ": chunk declares " + std::to_string(uncompressed_size) +
                              " bytes of records: the chunk is corrupt");
  if (compression.empty()) {
    if (n != uncompressed_size)
      throw DataError(file, where + ": uncompressed chunk holds " + std::to_string(n) + " bytes of records, it says " +
                                std::to_string(uncompressed_size));
    out.assign(src, src + n);
  } else if (compression == "zstd") {
    zstd_decompress(src, n, uncompressed_size, out, file, where);
  } else if (compression == "lz4") {
    lz4_decompress(src, n, uncompressed_size, out, file, where);
  } else {
    throw DataError(file, where + ": unknown chunk compression '" + compression + "' (supported: zstd, lz4, none)");
  }
}

std::vector<uint8_t> decompress(const std::string &compression, const uint8_t *src, size_t n,
                                uint64_t uncompressed_size, const std::string &file, const std::string &where) {
  std::vector<uint8_t> out;
  decompress_into(compression, src, n, uncompressed_size, out, file, where);
  return out;
}

std::vector<uint8_t> compress(const std::string &compression, const uint8_t *src, size_t n) {
  if (compression.empty())
    return std::vector<uint8_t>(src, src + n);
  std::vector<uint8_t> out;
  if (compression == "zstd") {
    out.resize(ZSTD_compressBound(n));
    // Level 1, zstd's fastest: an export or a run's log is written while the user waits.
    const size_t r = ZSTD_compress(out.data(), out.size(), src, n, 1);
    if (ZSTD_isError(r))
      throw std::runtime_error(std::string("zstd compression failed: ") + ZSTD_getErrorName(r));
    out.resize(r);
    return out;
  }
  if (compression == "lz4") {
    LZ4F_preferences_t prefs;
    std::memset(&prefs, 0, sizeof prefs);
    prefs.frameInfo.contentSize = n;
    out.resize(LZ4F_compressFrameBound(n, &prefs));
    const size_t r = LZ4F_compressFrame(out.data(), out.size(), src, n, &prefs);
    if (LZ4F_isError(r))
      throw std::runtime_error(std::string("lz4 compression failed: ") + LZ4F_getErrorName(r));
    out.resize(r);
    return out;
  }
  throw UsageError("unknown MCAP chunk compression '" + compression + "' (expected zstd, lz4 or none)");
}

} // namespace ovton::core::mcap
