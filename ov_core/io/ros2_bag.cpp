// rosbag2 folders: metadata.yaml names the storage (mcap or sqlite3), the split files in order and the compression;
// the files are read as one recording (ros2_recording.h).
#include "ov_core/io/mcap_format.h"
#include "ov_core/io/ros2_reader.h"
#include "ov_core/io/ros2_recording.h"
#include "ov_core/types/errors.h"

#include <yaml-cpp/yaml.h>
#include <zstd.h>

#include <filesystem>

namespace fs = std::filesystem;

namespace ovton::core {

namespace {

/// rosbag2's per-message compression (compression_mode MESSAGE): each message's CDR bytes are one zstd frame.
class ZstdMessagesFile : public RecordingFile {
public:
  explicit ZstdMessagesFile(std::unique_ptr<RecordingFile> inner) : inner_(std::move(inner)) {}
  const std::string &path() const override { return inner_->path(); }
  std::string cut() const override { return inner_->cut(); }

  void scan(uint32_t file_index,
            const std::function<void(const std::string &, const std::string &, const std::string &)> &on_topic,
            const std::function<size_t(const std::string &)> &prefix,
            const std::function<void(const ScannedMessage &)> &on_message) override {
    const auto whole = [&](const std::string &topic) -> size_t { return prefix(topic) == 0 ? 0 : SIZE_MAX; };
    inner_->scan(file_index, on_topic, whole, [&](const ScannedMessage &m) {
      const std::vector<uint8_t> plain = unpack(m.data, m.size, m.location);
      ScannedMessage u = m;
      u.data = plain.data();
      u.size = u.full_size = plain.size();
      on_message(u);
    });
  }

  std::vector<uint8_t> fetch(const MessagePlace &p) const override {
    const std::vector<uint8_t> packed = inner_->fetch(p);
    return unpack(packed.data(), packed.size(), " (compressed message)");
  }

private:
  std::vector<uint8_t> unpack(const uint8_t *data, size_t size, const std::string &where) const {
    const unsigned long long n = ZSTD_getFrameContentSize(data, size);
    if (n == ZSTD_CONTENTSIZE_ERROR || n == ZSTD_CONTENTSIZE_UNKNOWN)
      throw DataError(path(), "message" + where + ": not a zstd frame with its size (compression_mode MESSAGE)");
    return mcap::decompress("zstd", data, size, n, path(), "message" + where);
  }

  std::unique_ptr<RecordingFile> inner_;
};

std::string text_of(const YAML::Node &n, const char *key) {
  return n[key] && n[key].IsScalar() ? n[key].as<std::string>() : std::string();
}

} // namespace

bool is_ros2_bag_folder(const std::string &path) {
  std::error_code ec;
  return fs::is_directory(path, ec) && fs::is_regular_file(fs::path(path) / "metadata.yaml", ec);
}

Dataset load_ros2_bag(const std::string &folder, const BagOptions &opt) {
  // A trailing slash would leave no name for the calibration files looked for beside the folder.
  fs::path dir = fs::path(folder).lexically_normal();
  if (!dir.has_filename())
    dir = dir.parent_path();
  const std::string meta_file = (dir / "metadata.yaml").string();
  if (!is_ros2_bag_folder(dir.string()))
    throw DataError(folder, "not a rosbag2 folder (no metadata.yaml)");
  YAML::Node info;
  try {
    info = YAML::LoadFile(meta_file)["rosbag2_bagfile_information"];
  } catch (const YAML::Exception &e) {
    throw DataError(meta_file, e.mark.line + 1, "unreadable YAML: " + e.msg);
  }
  if (!info || !info.IsMap())
    throw DataError(meta_file, "no rosbag2_bagfile_information: not a rosbag2 metadata file");
  const std::string storage = text_of(info, "storage_identifier");
  const std::string mode = text_of(info, "compression_mode"), format = text_of(info, "compression_format");
  const bool per_message = mode == "MESSAGE";
  if (mode == "FILE")
    throw DataError(meta_file, "the bag's files are compressed as whole files (compression_mode FILE, " + format +
                                   "): decompress them first (ros2 bag decompress, or zstd -d and edit metadata.yaml)");
  if (per_message && format != "zstd")
    throw DataError(meta_file, "per-message compression '" + format + "' is not supported (zstd is)");
  const YAML::Node paths = info["relative_file_paths"];
  if (!paths || !paths.IsSequence() || paths.size() == 0)
    throw DataError(meta_file, "no relative_file_paths: the bag lists no files");

  std::vector<std::shared_ptr<RecordingFile>> files;
  std::string listed;
  for (const YAML::Node &p : paths) {
    const std::string rel = p.IsScalar() ? p.as<std::string>() : std::string();
    // Older rosbag2 versions wrote the bag folder's name in front of each file's.
    fs::path file = dir / rel;
    std::error_code ec;
    if (!fs::is_regular_file(file, ec))
      file = dir / fs::path(rel).filename();
    if (rel.empty() || !fs::is_regular_file(file, ec))
      throw DataError(meta_file, "listed file '" + rel + "' is not in " + dir.string());
    const std::string ext = file.extension().string();
    const bool mcap = storage == "mcap" || (storage.empty() && ext == ".mcap");
    const bool sqlite = storage == "sqlite3" || (storage.empty() && ext == ".db3");
    if (!mcap && !sqlite)
      throw DataError(meta_file, "storage '" + storage + "' is not supported (mcap, sqlite3)");
    std::unique_ptr<RecordingFile> f = mcap ? open_mcap_recording(file.string()) : open_sqlite_recording(file.string());
    if (per_message)
      f = std::make_unique<ZstdMessagesFile>(std::move(f));
    files.push_back(std::move(f));
    listed += (listed.empty() ? "" : ", ") + file.filename().string();
  }
  return build_ros2_dataset(dir.string(), "ros2bag", std::move(files), opt,
                            "; files " + listed + " (" + (storage.empty() ? "storage by extension" : storage) +
                                (per_message ? ", zstd per message" : "") + ")");
}

} // namespace ovton::core
