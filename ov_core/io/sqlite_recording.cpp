// A rosbag2 SQLite database (.db3: tables topics and messages, CDR messages as blobs) as one file of a ROS 2 recording
// (ros2_recording.h), read with Debian's SQLite. An image's first bytes are read through SQLite's incremental blob
// I/O, so a load reads the IMU and the images' headers, not the pixels.
#include "ov_core/io/ros2_recording.h"
#include "ov_core/types/errors.h"

#include <sqlite3.h>

#include <cstdint>
#include <map>
#include <mutex>

namespace ovton::core {

namespace {

class SqliteRecordingFile : public RecordingFile {
public:
  explicit SqliteRecordingFile(const std::string &path) : path_(path) {
    if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
      const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      db_ = nullptr;
      throw DataError(path, "cannot open the rosbag2 SQLite database: " + why);
    }
  }
  ~SqliteRecordingFile() override { sqlite3_close(db_); }
  const std::string &path() const override { return path_; }

  void scan(uint32_t file_index,
            const std::function<void(const std::string &, const std::string &, const std::string &)> &on_topic,
            const std::function<size_t(const std::string &)> &prefix,
            const std::function<void(const ScannedMessage &)> &on_message) override {
    std::map<int64_t, std::string> topic_of;
    {
      Statement s(*this, "SELECT id, name, type, serialization_format FROM topics ORDER BY id");
      while (s.step()) {
        const std::string name = s.text(1);
        topic_of[s.integer(0)] = name;
        on_topic(name, s.text(2), s.text(3));
      }
    }
    // length() of a blob is read from the row's header, without the blob itself.
    Statement s(*this, "SELECT id, topic_id, length(data) FROM messages ORDER BY timestamp, id");
    std::vector<uint8_t> buf;
    while (s.step()) {
      const int64_t row = s.integer(0);
      const auto topic = topic_of.find(s.integer(1));
      if (topic == topic_of.end())
        fail("message row " + std::to_string(row) + " refers to topic id " + std::to_string(s.integer(1)) +
             ", which the topics table does not list");
      const size_t want = prefix(topic->second);
      if (want == 0)
        continue;
      const uint64_t size = static_cast<uint64_t>(s.integer(2));
      buf = read_blob(row, want < size ? want : size);
      ScannedMessage m;
      m.topic = &topic->second;
      m.data = buf.data();
      m.size = buf.size();
      m.full_size = size;
      m.place.file = file_index;
      m.place.chunk = -2;
      m.place.offset = static_cast<uint64_t>(row);
      m.place.size = size;
      m.location = " (row " + std::to_string(row) + ")";
      on_message(m);
    }
  }

  std::vector<uint8_t> fetch(const MessagePlace &p) const override {
    std::lock_guard<std::mutex> lock(mutex_);
    return read_blob(static_cast<int64_t>(p.offset), p.size);
  }

private:
  [[noreturn]] void fail(const std::string &what) const { throw DataError(path_, what); }

  std::vector<uint8_t> read_blob(int64_t row, uint64_t n) const {
    sqlite3_blob *blob = nullptr;
    if (sqlite3_blob_open(db_, "main", "messages", "data", row, 0, &blob) != SQLITE_OK) {
      sqlite3_blob_close(blob);
      fail("message row " + std::to_string(row) + ": " + sqlite3_errmsg(db_));
    }
    const uint64_t have = static_cast<uint64_t>(sqlite3_blob_bytes(blob));
    std::vector<uint8_t> out(static_cast<size_t>(n < have ? n : have));
    const int rc = out.empty() ? SQLITE_OK : sqlite3_blob_read(blob, out.data(), static_cast<int>(out.size()), 0);
    sqlite3_blob_close(blob);
    if (rc != SQLITE_OK)
      fail("message row " + std::to_string(row) + ": " + sqlite3_errstr(rc) + " (the database is damaged)");
    return out;
  }

  /// A prepared statement whose failures name the database.
  class Statement {
  public:
    Statement(const SqliteRecordingFile &f, const char *sql) : f_(f) {
      if (sqlite3_prepare_v2(f.db_, sql, -1, &s_, nullptr) != SQLITE_OK)
        f.fail(std::string("not a rosbag2 database (") + sqlite3_errmsg(f.db_) + ")");
    }
    ~Statement() { sqlite3_finalize(s_); }
    bool step() {
      const int rc = sqlite3_step(s_);
      if (rc != SQLITE_ROW && rc != SQLITE_DONE)
        f_.fail(std::string("reading failed: ") + sqlite3_errmsg(f_.db_) + " (the database is damaged or cut)");
      return rc == SQLITE_ROW;
    }
    int64_t integer(int col) { return sqlite3_column_int64(s_, col); }
    std::string text(int col) {
      const unsigned char *t = sqlite3_column_text(s_, col);
      return t ? std::string(reinterpret_cast<const char *>(t)) : std::string();
    }

  private:
    const SqliteRecordingFile &f_;
    sqlite3_stmt *s_ = nullptr;
  };

  std::string path_;
  sqlite3 *db_ = nullptr;
  mutable std::mutex mutex_;
};

} // namespace

std::unique_ptr<RecordingFile> open_sqlite_recording(const std::string &path) {
  return std::make_unique<SqliteRecordingFile>(path);
}

} // namespace ovton::core
