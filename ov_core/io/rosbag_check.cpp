#include "ov_core/io/rosbag_check.h"
#include "ov_core/types/errors.h"

#include <roslz4/lz4s.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <set>
#include <vector>

namespace ovton::core {

namespace {

constexpr size_t kMagic = 13; // "#ROSBAG V2.0\n"
/// A chunk's records, uncompressed: rosbag writes chunks of about 768 kB; anything past this is a damaged size field.
constexpr uint64_t kMaxChunkBytes = uint64_t{1} << 30;

/// What a user can do with a bag cut short (a recorder that crashed): ROS's own tool rebuilds the index from the
/// messages that made it to disk; ovton reads ROS 1 bags through their index.
const std::string kReindex = " (a recording cut short? `rosbag reindex` rebuilds its index from the messages it holds)";

enum Op : uint8_t { kMessageData = 2, kBagHeader = 3, kIndexData = 4, kChunk = 5, kChunkInfo = 6, kConnection = 7 };

uint32_t le32(const uint8_t *p) {
  return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 | static_cast<uint32_t>(p[2]) << 16 |
         static_cast<uint32_t>(p[3]) << 24;
}

uint64_t le64(const uint8_t *p) {
  return static_cast<uint64_t>(le32(p)) | static_cast<uint64_t>(le32(p + 4)) << 32;
}

/// The header fields the checks need.
struct Header {
  uint8_t op = 0;
  std::string compression;
  uint64_t size = 0, index_pos = 0, chunk_pos = 0, count = 0;
  bool has_size = false, has_chunk_pos = false, has_count = false;
};

/// A record in a range of bytes: where its header and data are.
struct Record {
  uint64_t pos = 0, data_at = 0, data_len = 0;
  Header h;
};

class Checker {
public:
  explicit Checker(const std::string &file) : file_(file), in_(file, std::ios::binary) {
    in_.seekg(0, std::ios::end);
    size_ = static_cast<uint64_t>(in_.tellg());
  }

  void run() {
    if (size_ < kMagic)
      throw DataError(file_, "not a ROS 1 bag (shorter than its magic)");
    for (uint64_t pos = kMagic; pos < size_;) {
      const Record r = next([&](uint64_t at, uint64_t n) { return read(at, n); }, pos, size_, "");
      const std::string where = "byte " + std::to_string(pos);
      if (r.h.op == kBagHeader && r.h.index_pos > size_)
        throw DataError(file_, where + ": the index position " + std::to_string(r.h.index_pos) +
                                   " lies past the end of the file: the bag is corrupt or truncated" + kReindex);
      if (r.h.op == kChunk)
        chunk(r, where);
      else if (r.h.op == kIndexData)
        index(r, where);
      else if (r.h.op == kChunkInfo && (!r.h.has_chunk_pos || !chunks_.count(r.h.chunk_pos)))
        throw DataError(file_, where + ": a chunk index points at byte " + std::to_string(r.h.chunk_pos) +
                                   ", where no chunk starts: the bag is corrupt");
      else if (r.h.op == kConnection)
        parse_header(read(r.data_at, r.data_len), where + " (connection header)");
      pos = r.data_at + r.data_len;
    }
  }

private:
  std::vector<uint8_t> read(uint64_t offset, uint64_t n) {
    std::vector<uint8_t> b(static_cast<size_t>(n));
    in_.seekg(static_cast<std::streamoff>(offset));
    in_.read(reinterpret_cast<char *>(b.data()), static_cast<std::streamsize>(n));
    if (static_cast<uint64_t>(in_.gcount()) != n)
      throw DataError(file_, "byte " + std::to_string(offset) + ": read failed");
    return b;
  }

  Header parse_header(const std::vector<uint8_t> &h, const std::string &where) const {
    Header out;
    for (size_t pos = 0; pos < h.size();) {
      if (h.size() - pos < 4 || le32(h.data() + pos) > h.size() - pos - 4)
        throw DataError(file_, where + ": a header field runs past its header: the bag is corrupt");
      const size_t len = le32(h.data() + pos);
      const char *f = reinterpret_cast<const char *>(h.data() + pos + 4);
      const void *eq = std::memchr(f, '=', len);
      if (!eq)
        throw DataError(file_, where + ": a header field without '=': the bag is corrupt");
      const std::string name(f, static_cast<const char *>(eq));
      const uint8_t *v = reinterpret_cast<const uint8_t *>(eq) + 1;
      const size_t n = len - name.size() - 1;
      if (name == "op" && n == 1)
        out.op = v[0];
      else if (name == "compression")
        out.compression.assign(reinterpret_cast<const char *>(v), n);
      else if (name == "size" && n == 4)
        out.size = le32(v), out.has_size = true;
      else if (name == "count" && n == 4)
        out.count = le32(v), out.has_count = true;
      else if (name == "index_pos" && n == 8)
        out.index_pos = le64(v);
      else if (name == "chunk_pos" && n == 8)
        out.chunk_pos = le64(v), out.has_chunk_pos = true;
      pos += 4 + len;
    }
    return out;
  }

  /// The record at `pos` of a range ending at `end`, read through `read`; its lengths must stay within the range.
  template <typename Read> Record next(Read read, uint64_t pos, uint64_t end, const std::string &in_chunk) {
    const std::string where = "byte " + std::to_string(pos) + in_chunk;
    const auto past = [&](const char *what) {
      return DataError(file_, where + ": the record's " + std::string(what) + " runs past the end of " +
                                  (in_chunk.empty() ? "the file (" + std::to_string(end) + " bytes)" : "its chunk") +
                                  ": the bag is corrupt or truncated" + (in_chunk.empty() ? kReindex : ""));
    };
    Record r;
    r.pos = pos;
    if (end - pos < 4)
      throw past("header length");
    const uint64_t header_len = le32(read(pos, 4).data());
    if (header_len > end - pos - 4)
      throw past("header");
    r.h = parse_header(read(pos + 4, header_len), where);
    const uint64_t len_at = pos + 4 + header_len;
    if (end - len_at < 4)
      throw past("data length");
    r.data_len = le32(read(len_at, 4).data());
    r.data_at = len_at + 4;
    if (r.data_len > end - r.data_at)
      throw past("data");
    return r;
  }

  /// A chunk's records, uncompressed (none) or decompressed (lz4), walked; bz2 chunks carry CRCs of their own.
  void chunk(const Record &r, const std::string &where) {
    if (!r.h.has_size || r.h.size > kMaxChunkBytes)
      throw DataError(file_, where + ": a chunk that declares " + (r.h.has_size ? std::to_string(r.h.size) : "no") +
                                 " size for its records: the bag is corrupt");
    chunks_.insert(r.pos);
    chunk_size_ = r.h.size;
    starts_.clear();
    walked_ = false;
    std::vector<uint8_t> records;
    if (r.h.compression == "none") {
      if (r.h.size != r.data_len)
        throw DataError(file_, where + ": an uncompressed chunk of " + std::to_string(r.data_len) + " bytes declares " +
                                   std::to_string(r.h.size) + ": the bag is corrupt");
      records = read(r.data_at, r.data_len);
    } else if (r.h.compression == "lz4") {
      std::vector<uint8_t> packed = read(r.data_at, r.data_len);
      records.resize(static_cast<size_t>(r.h.size));
      unsigned int n = static_cast<unsigned int>(records.size());
      if (roslz4_buffToBuffDecompress(reinterpret_cast<char *>(packed.data()), static_cast<unsigned int>(packed.size()),
                                      reinterpret_cast<char *>(records.data()), &n) != ROSLZ4_OK ||
          n != r.h.size)
        throw DataError(file_, where + ": an lz4 chunk that does not decompress to its declared " +
                                   std::to_string(r.h.size) + " bytes: the bag is corrupt");
    } else {
      return;
    }
    const auto in_memory = [&](uint64_t at, uint64_t n) {
      return std::vector<uint8_t>(records.begin() + static_cast<std::ptrdiff_t>(at),
                                  records.begin() + static_cast<std::ptrdiff_t>(at + n));
    };
    const std::string in_chunk = " of the chunk at " + where;
    for (uint64_t pos = 0; pos < records.size();) {
      const Record inner = next(in_memory, pos, records.size(), in_chunk);
      if (inner.h.op == kConnection)
        parse_header(in_memory(inner.data_at, inner.data_len), "byte " + std::to_string(pos) + in_chunk);
      starts_.insert(pos);
      pos = inner.data_at + inner.data_len;
    }
    walked_ = true;
  }

  /// A chunk's index (after it): entries of 12 bytes whose offsets are records of that chunk.
  void index(const Record &r, const std::string &where) {
    if (!r.h.has_count || r.h.count * 12 != r.data_len)
      throw DataError(file_, where + ": an index record whose count does not fit its data: the bag is corrupt");
    const std::vector<uint8_t> entries = read(r.data_at, r.data_len);
    for (uint64_t i = 0; i < r.h.count; ++i) {
      const uint32_t offset = le32(entries.data() + 12 * i + 8);
      if (offset >= chunk_size_ || (walked_ && !starts_.count(offset)))
        throw DataError(file_, where + ": index entry " + std::to_string(i) + " points at offset " +
                                   std::to_string(offset) +
                                   " of its chunk, where no record starts: the bag is corrupt");
    }
  }

  std::string file_;
  std::ifstream in_;
  uint64_t size_ = 0;
  std::set<uint64_t> chunks_; ///< positions of the chunk records met so far
  uint64_t chunk_size_ = 0;   ///< the last chunk's records, uncompressed
  std::set<uint64_t> starts_; ///< where the last chunk's records start, when walked
  bool walked_ = false;
};

} // namespace

void check_rosbag_structure(const std::string &file) {
  Checker(file).run();
}

} // namespace ovton::core
