// An MCAP file as one file of a ROS 2 recording (ros2_recording.h), and load_mcap.
#include "ov_core/io/mcap_format.h"
#include "ov_core/io/mcap_reader.h"
#include "ov_core/io/ros2_reader.h"
#include "ov_core/io/ros2_recording.h"
#include "ov_core/types/errors.h"

#include <cstring>
#include <fstream>
#include <map>

namespace ovton::core {

namespace {

class McapRecordingFile : public RecordingFile {
public:
  explicit McapRecordingFile(const std::string &path) : reader_(path) {}
  const std::string &path() const override { return reader_.file(); }
  std::string cut() const override { return cut_; }

  void scan(uint32_t file_index,
            const std::function<void(const std::string &, const std::string &, const std::string &)> &on_topic,
            const std::function<size_t(const std::string &)> &prefix,
            const std::function<void(const ScannedMessage &)> &on_message) override {
    std::map<uint16_t, std::string> topic_of;
    const McapScan s = reader_.scan(
        [&](const McapChannel &c) {
          topic_of[c.id] = c.topic;
          on_topic(c.topic, c.schema_name, c.message_encoding);
        },
        [&](const McapMessage &m) {
          const std::string &topic = topic_of.at(m.channel_id);
          if (prefix(topic) == 0)
            return;
          ScannedMessage sm;
          sm.topic = &topic;
          sm.data = m.data;
          sm.size = sm.full_size = m.size;
          sm.place.file = file_index;
          sm.place.chunk = m.ref.chunk;
          sm.place.offset = m.ref.offset;
          sm.place.size = m.ref.size;
          sm.location = (m.ref.chunk >= 0 ? " in the chunk at byte " : " at byte ") + std::to_string(m.record_offset);
          on_message(sm);
        });
    cut_ = s.complete ? std::string() : s.cut_reason;
  }

  std::vector<uint8_t> fetch(const MessagePlace &p) const override {
    McapMessageRef ref;
    ref.chunk = p.chunk;
    ref.offset = p.offset;
    ref.size = p.size;
    return reader_.fetch(ref);
  }

private:
  McapReader reader_;
  std::string cut_;
};

} // namespace

std::unique_ptr<RecordingFile> open_mcap_recording(const std::string &path) {
  return std::make_unique<McapRecordingFile>(path);
}

bool is_mcap_file(const std::string &path) {
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  return in.read(magic, 8) && std::memcmp(magic, mcap::kMagic, 8) == 0;
}

Dataset load_mcap(const std::string &file, const BagOptions &opt) {
  std::vector<std::shared_ptr<RecordingFile>> files;
  files.push_back(open_mcap_recording(file));
  return build_ros2_dataset(file, "mcap", std::move(files), opt);
}

} // namespace ovton::core
