#pragma once
// Writing an MCAP file (mcap_format.h): messages grouped in chunks (zstd, lz4 or uncompressed) with a message index
// after each chunk, then a summary (schemas, channels, chunk indexes, statistics, summary offsets) and the footer, so
// that indexed readers (Foxglove, ros2 bag play, the mcap CLI) can seek; without the summary the file is what a
// recorder that stopped early leaves (tests of the reader use both).
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace ovton::core {

struct McapWriteOptions {
  std::string compression = "zstd"; ///< zstd | lz4 | none
  size_t chunk_size = 1u << 20;     ///< records are collected until a chunk holds this many bytes
  bool chunked = true;              ///< false: every record directly in the data section (no compression, no index)
  bool summary = true;              ///< summary section and summary offsets (message indexes follow chunks anyway)
  std::string profile = "ros2";
  std::string library = "ovton";
};

class McapWriter {
public:
  /// Creates `path` (truncating it). Throws DataError naming it when it cannot be written.
  McapWriter(const std::string &path, const McapWriteOptions &opt = {});
  /// Closes the file as it is when close() was not called: a file without its end, as a crash leaves one.
  ~McapWriter();
  McapWriter(const McapWriter &) = delete;
  McapWriter &operator=(const McapWriter &) = delete;

  uint16_t add_schema(const std::string &name, const std::string &encoding, const std::string &data);
  uint16_t add_channel(const std::string &topic, uint16_t schema_id, const std::string &message_encoding,
                       const std::map<std::string, std::string> &metadata = {});
  void write(uint16_t channel_id, uint64_t log_time, uint64_t publish_time, const uint8_t *data, size_t size);
  void write(uint16_t channel_id, uint64_t log_time, const std::vector<uint8_t> &data) {
    write(channel_id, log_time, log_time, data.data(), data.size());
  }
  /// Writes the last chunk, the Data End record, the summary and the footer.
  void close();
  uint64_t bytes_written() const { return offset_; }
  /// Messages written per channel id.
  const std::map<uint16_t, uint64_t> &message_counts() const { return counts_; }

private:
  struct ChunkIndex {
    uint64_t start_time, end_time, offset, length, index_length, compressed_size, uncompressed_size;
    std::map<uint16_t, uint64_t> index_offsets;
  };
  void emit(const std::vector<uint8_t> &bytes);
  void record(std::vector<uint8_t> &out, uint8_t op, const std::vector<uint8_t> &content);
  void data_record(uint8_t op, const std::vector<uint8_t> &content);
  void flush_chunk();

  std::string path_;
  McapWriteOptions opt_;
  std::FILE *f_ = nullptr;
  bool closed_ = false;
  uint64_t offset_ = 0;
  uint32_t data_crc_ = 0, summary_crc_ = 0;
  bool in_summary_ = false;
  std::vector<std::vector<uint8_t>> schemas_, channels_; ///< records' content, repeated in the summary
  std::vector<uint8_t> chunk_;                           ///< records of the open chunk
  uint64_t chunk_start_ = 0, chunk_end_ = 0;
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_index_; ///< per channel: log time, offset
  std::vector<ChunkIndex> chunk_indexes_;
  std::map<uint16_t, uint64_t> counts_;
  std::map<uint16_t, uint32_t> sequence_;
  uint64_t message_count_ = 0, first_time_ = 0, last_time_ = 0;
};

} // namespace ovton::core
