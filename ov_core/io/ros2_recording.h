#pragma once
// ROS 2 recordings (MCAP files and rosbag2 folders) become a Dataset here, whatever file format holds the messages:
// each file is walked once in recording order (RecordingFile::scan), the camera and IMU topics are chosen, images are
// checked by their headers and left in the file, and the calibration comes from the user, from files beside the
// recording, or from the recording's own sensor_msgs/CameraInfo and /tf_static. Internal to the readers in ov_core/io.
#include "ov_core/io/dataset.h"
#include "ov_core/io/rosbag_reader.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ovton::core {

/// Where a message's bytes are, for the file that found it: an MCAP chunk (chunk >= 0) and the offset in its records,
/// a byte offset of an MCAP file (chunk -1), or a SQLite row id (chunk -2).
struct MessagePlace {
  uint32_t file = 0;
  int64_t chunk = -1;
  uint64_t offset = 0, size = 0;
};

/// One message as a file's walk hands it over. `size` bytes are in memory at `data`; a file asked for only the
/// first bytes of a message (RecordingFile::scan's `prefix`) may give fewer than the message's `full_size`.
struct ScannedMessage {
  const std::string *topic = nullptr;
  const uint8_t *data = nullptr;
  size_t size = 0, full_size = 0;
  MessagePlace place;
  std::string location; ///< where in the file, for errors (" at byte N"), "" when the file has no byte offsets
};

/// One file of a recording (a .mcap file or a rosbag2 .db3 database).
class RecordingFile {
public:
  virtual ~RecordingFile() = default;
  virtual const std::string &path() const = 0;
  /// Walks the file in recording order. on_topic(topic, type, encoding) when a topic is first seen; then for each
  /// message, prefix(topic) says how many of its first bytes are needed (0: skip it, SIZE_MAX: all) and on_message
  /// gets them. Throws DataError naming the file and the place of damage.
  virtual void scan(uint32_t file_index,
                    const std::function<void(const std::string &, const std::string &, const std::string &)> &on_topic,
                    const std::function<size_t(const std::string &)> &prefix,
                    const std::function<void(const ScannedMessage &)> &on_message) = 0;
  /// The whole message at `p` (found by scan). Safe to call from several threads.
  virtual std::vector<uint8_t> fetch(const MessagePlace &p) const = 0;
  /// After scan: empty when the file was complete, else where and why it ends early.
  virtual std::string cut() const { return std::string(); }
};

std::unique_ptr<RecordingFile> open_mcap_recording(const std::string &path);
std::unique_ptr<RecordingFile> open_sqlite_recording(const std::string &path);

/// The Dataset of a recording made of `files` (in order; a rosbag2 folder's split files), named `root` (the file or
/// folder the user gave). `kind` is "mcap" or "ros2bag"; `extra_notes` is added to Dataset::notes.
Dataset build_ros2_dataset(const std::string &root, const std::string &kind,
                           std::vector<std::shared_ptr<RecordingFile>> files, const BagOptions &opt,
                           const std::string &extra_notes = "");

} // namespace ovton::core
