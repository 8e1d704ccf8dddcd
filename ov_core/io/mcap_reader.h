#pragma once
// Reading an MCAP file message by message in file order, streamed: the data section is walked record by record (a
// chunk is decompressed, its CRC checked, its records walked, then dropped), so the summary and the indexes are not
// needed — a recording cut short by a crash has none — and memory does not grow with the file. A message's bytes can
// be fetched again later from where the walk found them (one decompressed chunk is kept for the next fetch).
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace ovton::core {

struct McapChannel {
  uint16_t id = 0;
  std::string topic, message_encoding;
  std::string schema_name, schema_encoding; ///< empty when the channel has no schema (schema_id 0)
  std::map<std::string, std::string> metadata;
};

/// Where a message's data lies: in the n-th chunk of the walk (chunk >= 0) at `offset` of its decompressed records,
/// or (chunk < 0) at `offset` of the file.
struct McapMessageRef {
  int64_t chunk = -1;
  uint64_t offset = 0;
  uint64_t size = 0;
};

struct McapMessage {
  uint16_t channel_id = 0;
  uint32_t sequence = 0;
  uint64_t log_time = 0, publish_time = 0;
  const uint8_t *data = nullptr; ///< valid during the callback only
  size_t size = 0;
  McapMessageRef ref;
  uint64_t record_offset = 0; ///< the file offset of the message's record, or of the chunk holding it
};

struct McapScan {
  size_t messages = 0, chunks = 0;
  bool complete = true;    ///< false: the file ends before its Data End record (a recording cut short)
  uint64_t cut_offset = 0; ///< where the last complete record ends, when !complete
  std::string cut_reason;  ///< what was found there, when !complete
};

class McapReader {
public:
  /// Opens `file` and checks the leading magic and the header record. Throws DataError naming the file otherwise.
  explicit McapReader(const std::string &file);
  ~McapReader();
  McapReader(const McapReader &) = delete;
  McapReader &operator=(const McapReader &) = delete;

  const std::string &file() const { return file_; }
  uint64_t file_size() const { return size_; }
  const std::string &profile() const { return profile_; }

  /// Walks the data section once, in file order: on_channel for each channel when it is first defined, on_message for
  /// every message. Chunks are checked against their CRC; a chunk that fails, an unknown compression or a malformed
  /// record throws DataError naming the file and the record's byte offset. A file that ends early (no Data End) is not
  /// an error here: the walk stops after the last complete record and says where (McapScan::complete).
  McapScan scan(const std::function<void(const McapChannel &)> &on_channel,
                const std::function<void(const McapMessage &)> &on_message);

  /// The data of a message found by scan(): read from the file directly when its chunk is uncompressed, else from
  /// the chunk decompressed (the last one is kept: a replay asks for the images in order). Safe to call from several
  /// threads.
  std::vector<uint8_t> fetch(const McapMessageRef &ref) const;

private:
  struct ChunkPlace {
    uint64_t record_offset, data_offset, compressed_size, uncompressed_size;
    std::string compression;
  };
  std::vector<uint8_t> read_at(uint64_t offset, uint64_t n, const std::string &what) const;
  void read_into(uint64_t offset, uint64_t n, const std::string &what, std::vector<uint8_t> &out) const;

  std::string file_, profile_;
  int fd_ = -1;
  uint64_t size_ = 0, data_start_ = 0;
  std::vector<ChunkPlace> chunks_;
  mutable std::mutex mutex_;
  mutable int64_t cached_chunk_ = -1;
  mutable std::vector<uint8_t> cached_, packed_; ///< the last compressed chunk fetched, decompressed; its bytes
};

} // namespace ovton::core
