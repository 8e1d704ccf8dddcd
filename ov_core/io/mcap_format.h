#pragma once
// The MCAP container format (https://mcap.dev/spec, major version 0), as ovton's reader and writer share it: magic,
// record opcodes, little-endian fields, CRC-32 and the chunk compressions (zstd, lz4 frames, none) through Debian's
// libzstd and liblz4. No MCAP library is packaged for Debian; this is written from the specification.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ovton::core::mcap {

inline constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum Op : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

/// Opcode (1 byte) and content length (uint64) before every record's content.
inline constexpr size_t kRecordPrefix = 9;
/// The footer record's content: summary_start, summary_offset_start (uint64), summary_crc (uint32).
inline constexpr size_t kFooterContent = 20;

/// Bounds-checked little-endian reading of one record's content; running past it throws DataError(file, where...).
class FieldReader {
public:
  FieldReader(const uint8_t *data, size_t size, std::string file, std::string where)
      : data_(data), size_(size), file_(std::move(file)), where_(std::move(where)) {}
  uint8_t u8(const char *field);
  uint16_t u16(const char *field);
  uint32_t u32(const char *field);
  uint64_t u64(const char *field);
  std::string string(const char *field);
  /// A field of `n` bytes: its place in the content (not copied).
  const uint8_t *bytes(size_t n, const char *field);
  /// A uint32 byte-length-prefixed map or array: its content's bytes, skipped past.
  std::pair<const uint8_t *, size_t> prefixed(const char *field);
  size_t position() const { return pos_; }
  size_t left() const { return size_ - pos_; }
  [[noreturn]] void fail(const std::string &what) const;

private:
  const uint8_t *data_;
  size_t size_, pos_ = 0;
  std::string file_, where_;
};

/// Little-endian appends for the writer.
void put_u8(std::vector<uint8_t> &b, uint8_t v);
void put_u16(std::vector<uint8_t> &b, uint16_t v);
void put_u32(std::vector<uint8_t> &b, uint32_t v);
void put_u64(std::vector<uint8_t> &b, uint64_t v);
void put_string(std::vector<uint8_t> &b, const std::string &s);
uint64_t get_u64(const uint8_t *p);

/// CRC-32 (ISO-HDLC, zlib's) of `n` bytes continuing `crc` (0 to start).
uint32_t crc32(uint32_t crc, const uint8_t *data, size_t n);

/// True for the chunk compressions ovton reads and writes: "zstd", "lz4" and "" (none).
bool compression_supported(const std::string &name);
/// Decompresses a chunk's records to exactly `uncompressed_size` bytes; memory grows with the output produced, not
/// with what a damaged size field claims. Throws DataError(file, where...) for damaged data or another size.
std::vector<uint8_t> decompress(const std::string &compression, const uint8_t *src, size_t n,
                                uint64_t uncompressed_size, const std::string &file, const std::string &where);
/// The same into `out`, whose memory is reused (a reader walking chunk after chunk allocates once).
void decompress_into(const std::string &compression, const uint8_t *src, size_t n, uint64_t uncompressed_size,
                     std::vector<uint8_t> &out, const std::string &file, const std::string &where);
/// Compresses a chunk's records ("zstd", "lz4" or "").
std::vector<uint8_t> compress(const std::string &compression, const uint8_t *src, size_t n);

} // namespace ovton::core::mcap
