#include "ov_core/io/mcap_reader.h"
#include "ov_core/io/mcap_format.h"
#include "ov_core/types/errors.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace ovton::core {

namespace {

std::string at_byte(const char *what, uint64_t offset) {
  return std::string(what) + " at byte " + std::to_string(offset);
}

/// Message record: channel_id, sequence, log_time, publish_time before the data.
constexpr size_t kMessageHeader = 2 + 4 + 8 + 8;

} // namespace

McapReader::McapReader(const std::string &file) : file_(file) {
  fd_ = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st {};
  if (fd_ < 0 || ::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
    if (fd_ >= 0)
      ::close(fd_);
    fd_ = -1;
    throw DataError(file, "MCAP file not found or unreadable");
  }
  size_ = static_cast<uint64_t>(st.st_size);
  if (size_ < 8 || std::memcmp(read_at(0, 8, "magic").data(), mcap::kMagic, 8) != 0) {
    ::close(fd_);
    fd_ = -1;
    throw DataError(file, "not an MCAP file (it does not start with the MCAP magic \\x89MCAP0\\r\\n)");
  }
  try {
    if (size_ < 8 + mcap::kRecordPrefix)
      throw DataError(file, "the file ends at byte " + std::to_string(size_) + ", before its header record");
    const auto prefix = read_at(8, mcap::kRecordPrefix, "header record");
    const uint64_t len = mcap::get_u64(prefix.data() + 1);
    if (prefix[0] != mcap::kHeader)
      throw DataError(file, "byte 8: the first record is not a Header (opcode " + std::to_string(prefix[0]) + ")");
    if (len > size_ - 8 - mcap::kRecordPrefix)
      throw DataError(file, "byte 8: the header record runs past the end of the file");
    const auto content = read_at(8 + mcap::kRecordPrefix, len, "header record");
    mcap::FieldReader r(content.data(), content.size(), file, at_byte("header record", 8));
    profile_ = r.string("profile");
    data_start_ = 8 + mcap::kRecordPrefix + len;
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
}

McapReader::~McapReader() {
  if (fd_ >= 0)
    ::close(fd_);
}

std::vector<uint8_t> McapReader::read_at(uint64_t offset, uint64_t n, const std::string &what) const {
  std::vector<uint8_t> out;
  read_into(offset, n, what, out);
  return out;
}

void McapReader::read_into(uint64_t offset, uint64_t n, const std::string &what, std::vector<uint8_t> &out) const {
  if (offset > size_ || n > size_ - offset)
    throw DataError(file_, at_byte(what.c_str(), offset) + ": " + std::to_string(n) +
                               " bytes would run past the end "
                               "of the file (" +
                               std::to_string(size_) + " bytes)");
  out.resize(static_cast<size_t>(n));
  uint64_t done = 0;
  while (done < n) {
    const ssize_t r = ::pread(fd_, out.data() + done, static_cast<size_t>(n - done), static_cast<off_t>(offset + done));
    if (r < 0 && errno == EINTR)
      continue;
    if (r <= 0)
      throw DataError(file_, at_byte(what.c_str(), offset) + ": read failed (" +
                                 (r < 0 ? std::string(std::strerror(errno)) : std::string("file shrank")) + ")");
    done += static_cast<uint64_t>(r);
  }
}

McapScan McapReader::scan(const std::function<void(const McapChannel &)> &on_channel,
                          const std::function<void(const McapMessage &)> &on_message) {
  struct SchemaInfo {
    std::string name, encoding;
  };
  std::map<uint16_t, SchemaInfo> schemas;
  std::map<uint16_t, bool> channels;
  McapScan out;
  chunks_.clear();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    cached_chunk_ = -1;
    cached_.clear();
  }

  // One record's content: `where` names it in errors; chunk < 0 for records outside chunks, whose messages are
  // fetched from `content_offset` of the file, else from that offset of the chunk's records.
  const auto handle = [&](uint8_t op, const uint8_t *p, size_t n, int64_t chunk, uint64_t content_offset,
                          uint64_t record_offset, const std::string &where) {
    mcap::FieldReader r(p, n, file_, where);
    if (op == mcap::kSchema) {
      const uint16_t id = r.u16("schema id");
      SchemaInfo s;
      s.name = r.string("schema name");
      s.encoding = r.string("schema encoding");
      if (id != 0) // id 0 is invalid and to be ignored (the spec)
        schemas[id] = std::move(s);
    } else if (op == mcap::kChannel) {
      McapChannel c;
      c.id = r.u16("channel id");
      const uint16_t schema_id = r.u16("schema id");
      c.topic = r.string("topic");
      c.message_encoding = r.string("message encoding");
      const auto [map, map_size] = r.prefixed("metadata");
      mcap::FieldReader m(map, map_size, file_, where);
      while (m.left() > 0) {
        std::string key = m.string("metadata key");
        c.metadata[key] = m.string("metadata value");
      }
      if (schema_id != 0) {
        const auto it = schemas.find(schema_id);
        if (it == schemas.end())
          r.fail("channel " + std::to_string(c.id) + " (" + c.topic + ") refers to schema " +
                 std::to_string(schema_id) + ", which no Schema record defines before it");
        c.schema_name = it->second.name;
        c.schema_encoding = it->second.encoding;
      }
      if (channels.emplace(c.id, true).second)
        on_channel(c);
    } else if (op == mcap::kMessage) {
      McapMessage m;
      m.channel_id = r.u16("channel id");
      m.sequence = r.u32("sequence");
      m.log_time = r.u64("log time");
      m.publish_time = r.u64("publish time");
      if (!channels.count(m.channel_id))
        r.fail("message on channel " + std::to_string(m.channel_id) + ", which no Channel record defines before it");
      m.data = p + kMessageHeader;
      m.size = n - kMessageHeader;
      m.ref.chunk = chunk;
      m.ref.offset = content_offset + kMessageHeader;
      m.ref.size = m.size;
      m.record_offset = record_offset;
      ++out.messages;
      on_message(m);
    }
  };

  uint64_t pos = data_start_;
  std::vector<uint8_t> content, records; // reused from record to record
  for (;;) {
    const auto cut = [&](const std::string &reason) {
      out.complete = false;
      out.cut_offset = pos;
      out.cut_reason = reason;
      return out;
    };
    if (pos == size_)
      return cut("the file ends at byte " + std::to_string(pos) + " without a Data End record or footer");
    if (size_ - pos < mcap::kRecordPrefix)
      return cut("the file ends at byte " + std::to_string(size_) + ", inside the record that starts at byte " +
                 std::to_string(pos));
    const auto prefix = read_at(pos, mcap::kRecordPrefix, "record");
    const uint8_t op = prefix[0];
    const uint64_t len = mcap::get_u64(prefix.data() + 1);
    const uint64_t content_at = pos + mcap::kRecordPrefix;
    if (len > size_ - content_at)
      return cut("the record at byte " + std::to_string(pos) + " (opcode " + std::to_string(op) + ") needs " +
                 std::to_string(len) + " bytes, the file ends " + std::to_string(size_ - content_at) +
                 " bytes after its start");
    if (op == mcap::kDataEnd || op == mcap::kFooter)
      return out;
    if (op == mcap::kSchema || op == mcap::kChannel || op == mcap::kMessage) {
      read_into(content_at, len, "record", content);
      if (op == mcap::kMessage && len < kMessageHeader)
        throw DataError(file_, at_byte("message record", pos) + ": " + std::to_string(len) + " bytes is too short");
      handle(op, content.data(), content.size(), -1, content_at, pos, at_byte("record", pos));
    } else if (op == mcap::kChunk) {
      const std::string where = at_byte("chunk", pos);
      read_into(content_at, len, "chunk", content);
      mcap::FieldReader r(content.data(), content.size(), file_, where);
      r.u64("message start time");
      r.u64("message end time");
      const uint64_t usize = r.u64("uncompressed size");
      const uint32_t crc = r.u32("uncompressed crc");
      const std::string compression = r.string("compression");
      const uint64_t csize = r.u64("records length");
      if (csize > r.left())
        r.fail("its records need " + std::to_string(csize) + " bytes, the chunk holds " + std::to_string(r.left()));
      const uint64_t records_at = r.position();
      mcap::decompress_into(compression, content.data() + records_at, csize, usize, records, file_, where);
      if (crc != 0 && mcap::crc32(0, records.data(), records.size()) != crc)
        throw DataError(file_, where + ": CRC mismatch in its " + std::to_string(records.size()) +
                                   " bytes of records: the chunk is corrupt");
      const int64_t index = static_cast<int64_t>(chunks_.size());
      chunks_.push_back({pos, content_at + records_at, csize, usize, compression});
      ++out.chunks;
      for (uint64_t at = 0; at < records.size();) {
        if (records.size() - at < mcap::kRecordPrefix)
          throw DataError(file_, where + ": its records end inside a record header at offset " + std::to_string(at));
        const uint8_t iop = records[at];
        const uint64_t ilen = mcap::get_u64(records.data() + at + 1);
        const uint64_t iat = at + mcap::kRecordPrefix;
        if (ilen > records.size() - iat)
          throw DataError(file_, where + ": the record at offset " + std::to_string(at) +
                                     " of its records runs past "
                                     "them (" +
                                     std::to_string(ilen) + " bytes)");
        if (iop == mcap::kMessage && ilen < kMessageHeader)
          throw DataError(file_, where + ": the message record at offset " + std::to_string(at) + " is too short");
        handle(iop, records.data() + iat, ilen, index, iat, pos, where);
        at = iat + ilen;
      }
    }
    // Message indexes, attachments, metadata and records of later versions of the format carry nothing ovton reads.
    pos = content_at + len;
  }
}

std::vector<uint8_t> McapReader::fetch(const McapMessageRef &ref) const {
  if (ref.chunk < 0)
    return read_at(ref.offset, ref.size, "message");
  std::lock_guard<std::mutex> lock(mutex_);
  if (ref.chunk >= static_cast<int64_t>(chunks_.size()))
    throw UsageError("McapReader::fetch: no chunk " + std::to_string(ref.chunk) + " in " + file_);
  const ChunkPlace &c = chunks_[static_cast<size_t>(ref.chunk)];
  const std::string where = at_byte("chunk", c.record_offset);
  if (ref.offset > c.uncompressed_size || ref.size > c.uncompressed_size - ref.offset)
    throw DataError(file_, where + ": a message lies past its records (the file changed since it was read)");
  if (c.compression.empty()) // the records are in the file as they are
    return read_at(c.data_offset + ref.offset, ref.size, where);
  if (cached_chunk_ != ref.chunk) {
    cached_chunk_ = -1;
    read_into(c.data_offset, c.compressed_size, where, packed_);
    mcap::decompress_into(c.compression, packed_.data(), packed_.size(), c.uncompressed_size, cached_, file_, where);
    cached_chunk_ = ref.chunk;
  }
  return std::vector<uint8_t>(cached_.begin() + static_cast<std::ptrdiff_t>(ref.offset),
                              cached_.begin() + static_cast<std::ptrdiff_t>(ref.offset + ref.size));
}

} // namespace ovton::core
