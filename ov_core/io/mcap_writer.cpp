#include "ov_core/io/mcap_writer.h"
#include "ov_core/io/mcap_format.h"
#include "ov_core/types/errors.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <tuple>

namespace ovton::core {

using namespace mcap;

namespace {

void put_bytes(std::vector<uint8_t> &b, const uint8_t *data, size_t n) {
  b.insert(b.end(), data, data + n);
}

void put_record_prefix(std::vector<uint8_t> &b, uint8_t op, uint64_t len) {
  put_u8(b, op);
  put_u64(b, len);
}

} // namespace

McapWriter::McapWriter(const std::string &path, const McapWriteOptions &opt) : path_(path), opt_(opt) {
  if (opt_.compression == "none")
    opt_.compression.clear();
  if (!compression_supported(opt_.compression) || (!opt_.chunked && !opt_.compression.empty()))
    throw UsageError("MCAP compression '" + opt.compression + "': expected zstd, lz4 or none" +
                     (opt_.chunked ? "" : " (none when not chunked)"));
  f_ = std::fopen(path.c_str(), "wb");
  if (!f_)
    throw DataError(path, std::string("cannot write the MCAP file: ") + std::strerror(errno));
  emit(std::vector<uint8_t>(kMagic, kMagic + 8));
  std::vector<uint8_t> header;
  put_string(header, opt_.profile);
  put_string(header, opt_.library);
  std::vector<uint8_t> rec;
  record(rec, kHeader, header);
  emit(rec);
}

McapWriter::~McapWriter() {
  if (f_)
    std::fclose(f_);
}

void McapWriter::emit(const std::vector<uint8_t> &bytes) {
  if (std::fwrite(bytes.data(), 1, bytes.size(), f_) != bytes.size())
    throw DataError(path_, "writing failed at byte " + std::to_string(offset_) + ": " + std::strerror(errno));
  data_crc_ = crc32(data_crc_, bytes.data(), bytes.size());
  if (in_summary_)
    summary_crc_ = crc32(summary_crc_, bytes.data(), bytes.size());
  offset_ += bytes.size();
}

void McapWriter::record(std::vector<uint8_t> &out, uint8_t op, const std::vector<uint8_t> &content) {
  put_record_prefix(out, op, content.size());
  put_bytes(out, content.data(), content.size());
}

void McapWriter::data_record(uint8_t op, const std::vector<uint8_t> &content) {
  if (opt_.chunked) {
    record(chunk_, op, content);
    return;
  }
  std::vector<uint8_t> rec;
  record(rec, op, content);
  emit(rec);
}

uint16_t McapWriter::add_schema(const std::string &name, const std::string &encoding, const std::string &data) {
  if (closed_ || schemas_.size() >= 0xfffe)
    throw UsageError("McapWriter: cannot add a schema to " + path_);
  const uint16_t id = static_cast<uint16_t>(schemas_.size() + 1); // 0 means "no schema"
  std::vector<uint8_t> c;
  put_u16(c, id);
  put_string(c, name);
  put_string(c, encoding);
  put_string(c, data);
  data_record(kSchema, c);
  schemas_.push_back(std::move(c));
  return id;
}

uint16_t McapWriter::add_channel(const std::string &topic, uint16_t schema_id, const std::string &message_encoding,
                                 const std::map<std::string, std::string> &metadata) {
  if (closed_ || channels_.size() >= 0xffff || schema_id > schemas_.size())
    throw UsageError("McapWriter: cannot add channel " + topic + " to " + path_);
  const uint16_t id = static_cast<uint16_t>(channels_.size());
  std::vector<uint8_t> c, map;
  put_u16(c, id);
  put_u16(c, schema_id);
  put_string(c, topic);
  put_string(c, message_encoding);
  for (const auto &[k, v] : metadata) {
    put_string(map, k);
    put_string(map, v);
  }
  put_u32(c, static_cast<uint32_t>(map.size()));
  put_bytes(c, map.data(), map.size());
  data_record(kChannel, c);
  channels_.push_back(std::move(c));
  counts_[id] = 0;
  return id;
}

void McapWriter::write(uint16_t channel_id, uint64_t log_time, uint64_t publish_time, const uint8_t *data,
                       size_t size) {
  if (closed_ || channel_id >= channels_.size())
    throw UsageError("McapWriter: no channel " + std::to_string(channel_id) + " in " + path_);
  std::vector<uint8_t> direct;
  std::vector<uint8_t> &out = opt_.chunked ? chunk_ : direct;
  if (opt_.chunked) {
    chunk_index_[channel_id].emplace_back(log_time, chunk_.size());
    chunk_start_ = chunk_.empty() ? log_time : std::min(chunk_start_, log_time);
    chunk_end_ = chunk_.empty() ? log_time : std::max(chunk_end_, log_time);
  }
  put_record_prefix(out, kMessage, 2 + 4 + 8 + 8 + size);
  put_u16(out, channel_id);
  put_u32(out, sequence_[channel_id]++);
  put_u64(out, log_time);
  put_u64(out, publish_time);
  put_bytes(out, data, size);
  if (!opt_.chunked)
    emit(direct);
  first_time_ = message_count_ == 0 ? log_time : std::min(first_time_, log_time);
  last_time_ = message_count_ == 0 ? log_time : std::max(last_time_, log_time);
  ++message_count_;
  ++counts_[channel_id];
  if (opt_.chunked && chunk_.size() >= opt_.chunk_size)
    flush_chunk();
}

void McapWriter::flush_chunk() {
  if (chunk_.empty())
    return;
  const std::vector<uint8_t> packed = compress(opt_.compression, chunk_.data(), chunk_.size());
  std::vector<uint8_t> c;
  const bool has_messages = !chunk_index_.empty();
  put_u64(c, has_messages ? chunk_start_ : 0);
  put_u64(c, has_messages ? chunk_end_ : 0);
  put_u64(c, chunk_.size());
  put_u32(c, crc32(0, chunk_.data(), chunk_.size()));
  put_string(c, opt_.compression);
  put_u64(c, packed.size());
  put_bytes(c, packed.data(), packed.size());
  ChunkIndex ci{};
  ci.start_time = has_messages ? chunk_start_ : 0;
  ci.end_time = has_messages ? chunk_end_ : 0;
  ci.offset = offset_;
  ci.compressed_size = packed.size();
  ci.uncompressed_size = chunk_.size();
  std::vector<uint8_t> rec;
  record(rec, kChunk, c);
  ci.length = rec.size();
  emit(rec);
  const uint64_t index_start = offset_;
  for (const auto &[channel, entries] : chunk_index_) {
    std::vector<uint8_t> m;
    put_u16(m, channel);
    put_u32(m, static_cast<uint32_t>(entries.size() * 16));
    for (const auto &[t, at] : entries) {
      put_u64(m, t);
      put_u64(m, at);
    }
    ci.index_offsets[channel] = offset_;
    std::vector<uint8_t> r;
    record(r, kMessageIndex, m);
    emit(r);
  }
  ci.index_length = offset_ - index_start;
  chunk_indexes_.push_back(std::move(ci));
  chunk_.clear();
  chunk_index_.clear();
  // The chunk and its indexes reach the file whole: a process killed later leaves them readable (no summary then).
  if (std::fflush(f_) != 0)
    throw DataError(path_, "writing failed at byte " + std::to_string(offset_) + ": " + std::strerror(errno));
}

void McapWriter::close() {
  if (closed_)
    return;
  flush_chunk();
  std::vector<uint8_t> end, rec;
  put_u32(end, data_crc_);
  record(rec, kDataEnd, end);
  emit(rec);
  uint64_t summary_start = 0, summary_offset_start = 0;
  in_summary_ = true;
  if (opt_.summary) {
    summary_start = offset_;
    std::vector<std::tuple<uint8_t, uint64_t, uint64_t>> groups;
    const auto group = [&](uint8_t op, const std::vector<std::vector<uint8_t>> &contents) {
      if (contents.empty())
        return;
      const uint64_t start = offset_;
      for (const auto &c : contents) {
        std::vector<uint8_t> r;
        record(r, op, c);
        emit(r);
      }
      groups.emplace_back(op, start, offset_ - start);
    };
    group(kSchema, schemas_);
    group(kChannel, channels_);
    std::vector<std::vector<uint8_t>> indexes;
    for (const ChunkIndex &ci : chunk_indexes_) {
      std::vector<uint8_t> c, map;
      put_u64(c, ci.start_time);
      put_u64(c, ci.end_time);
      put_u64(c, ci.offset);
      put_u64(c, ci.length);
      for (const auto &[ch, at] : ci.index_offsets) {
        put_u16(map, ch);
        put_u64(map, at);
      }
      put_u32(c, static_cast<uint32_t>(map.size()));
      put_bytes(c, map.data(), map.size());
      put_u64(c, ci.index_length);
      put_string(c, opt_.compression);
      put_u64(c, ci.compressed_size);
      put_u64(c, ci.uncompressed_size);
      indexes.push_back(std::move(c));
    }
    group(kChunkIndex, indexes);
    std::vector<uint8_t> stats, counts;
    put_u64(stats, message_count_);
    put_u16(stats, static_cast<uint16_t>(schemas_.size()));
    put_u32(stats, static_cast<uint32_t>(channels_.size()));
    put_u32(stats, 0); // attachments
    put_u32(stats, 0); // metadata
    put_u32(stats, static_cast<uint32_t>(chunk_indexes_.size()));
    put_u64(stats, first_time_);
    put_u64(stats, last_time_);
    for (const auto &[ch, n] : counts_) {
      put_u16(counts, ch);
      put_u64(counts, n);
    }
    put_u32(stats, static_cast<uint32_t>(counts.size()));
    put_bytes(stats, counts.data(), counts.size());
    group(kStatistics, {stats});
    summary_offset_start = offset_;
    for (const auto &[op, start, length] : groups) {
      std::vector<uint8_t> c, r;
      put_u8(c, op);
      put_u64(c, start);
      put_u64(c, length);
      record(r, kSummaryOffset, c);
      emit(r);
    }
  }
  // The footer's CRC covers the summary sections and the footer's own fields before it.
  std::vector<uint8_t> footer;
  put_record_prefix(footer, kFooter, kFooterContent);
  put_u64(footer, summary_start);
  put_u64(footer, summary_offset_start);
  const uint32_t crc = opt_.summary ? crc32(summary_crc_, footer.data(), footer.size()) : 0;
  put_u32(footer, crc);
  emit(footer);
  emit(std::vector<uint8_t>(kMagic, kMagic + 8));
  closed_ = true;
  const bool ok = std::fflush(f_) == 0;
  std::fclose(f_);
  f_ = nullptr;
  if (!ok)
    throw DataError(path_, std::string("writing failed at the end: ") + std::strerror(errno));
}

} // namespace ovton::core
