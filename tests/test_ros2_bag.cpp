// rosbag2 folders (metadata.yaml with split .mcap files or a SQLite .db3, messages optionally zstd-compressed one by
// one) read as the folder they were made from, and compressed images in ROS 1 bags replayed like raw ones. The .db3
// files here are written by the test itself through SQLite, with rosbag2's tables; a bag written by an independent
// writer is tested in test_ros2_external.cpp.
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_store.h"
#include "ov_core/io/mcap_export.h"
#include "ov_core/io/mcap_reader.h"
#include "ov_core/io/mcap_writer.h"
#include "ov_core/io/ros2_reader.h"
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/io/rosbag_writer.h"
#include "ov_sim/simulator.h"
#include "test_mcap_util.h"

#include <gtest/gtest.h>

#include <sqlite3.h>
#include <zstd.h>

#include <cstring>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using namespace ovton::core;

namespace {

struct Msg {
  std::string topic, type;
  uint64_t t;
  std::vector<uint8_t> data;
};

/// Every message of an MCAP file, with its topic's type.
std::vector<Msg> messages_of(const std::string &file) {
  McapReader r(file);
  std::map<uint16_t, std::pair<std::string, std::string>> ch;
  std::vector<Msg> out;
  r.scan(
      [&](const McapChannel &c) {
        ch[c.id] = {c.topic, c.schema_name};
      },
      [&](const McapMessage &m) {
        out.push_back({ch[m.channel_id].first, ch[m.channel_id].second, m.log_time,
                       std::vector<uint8_t>(m.data, m.data + m.size)});
      });
  return out;
}

void write_split_mcap(const std::vector<Msg> &msgs, size_t from, size_t to, const std::string &file) {
  McapWriter w(file);
  std::map<std::string, uint16_t> ch;
  for (size_t i = from; i < to; ++i) {
    const Msg &m = msgs[i];
    if (!ch.count(m.topic))
      ch[m.topic] = w.add_channel(m.topic, w.add_schema(m.type, "ros2msg", ""), "cdr");
    w.write(ch[m.topic], m.t, m.data);
  }
  w.close();
}

void exec(sqlite3 *db, const std::string &sql) {
  char *err = nullptr;
  ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err), SQLITE_OK) << (err ? err : "");
}

/// A rosbag2 SQLite database with rosbag2's tables (Humble's layout); zstd-compresses each message when asked.
void write_db3(const std::vector<Msg> &msgs, const std::string &file, bool zstd_messages) {
  sqlite3 *db = nullptr;
  ASSERT_EQ(sqlite3_open(file.c_str(), &db), SQLITE_OK);
  exec(db, "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
           "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL);"
           "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,timestamp INTEGER NOT NULL,"
           "data BLOB NOT NULL);CREATE INDEX timestamp_idx ON messages (timestamp ASC);BEGIN;");
  std::map<std::string, int> ids;
  sqlite3_stmt *ins = nullptr;
  sqlite3_prepare_v2(db, "INSERT INTO messages(topic_id, timestamp, data) VALUES(?, ?, ?)", -1, &ins, nullptr);
  for (const Msg &m : msgs) {
    if (!ids.count(m.topic)) {
      ids[m.topic] = static_cast<int>(ids.size()) + 1;
      exec(db, "INSERT INTO topics VALUES(" + std::to_string(ids[m.topic]) + ",'" + m.topic + "','" + m.type +
                   "','cdr','')");
    }
    std::vector<uint8_t> data = m.data;
    if (zstd_messages) {
      data.resize(ZSTD_compressBound(m.data.size()));
      data.resize(ZSTD_compress(data.data(), data.size(), m.data.data(), m.data.size(), 1));
    }
    sqlite3_bind_int(ins, 1, ids[m.topic]);
    sqlite3_bind_int64(ins, 2, static_cast<int64_t>(m.t));
    sqlite3_bind_blob(ins, 3, data.data(), static_cast<int>(data.size()), SQLITE_TRANSIENT);
    ASSERT_EQ(sqlite3_step(ins), SQLITE_DONE);
    sqlite3_reset(ins);
  }
  sqlite3_finalize(ins);
  exec(db, "COMMIT;");
  sqlite3_close(db);
}

void write_metadata(const std::string &dir, const std::string &storage, const std::vector<std::string> &files,
                    const std::string &compression_mode = "") {
  std::ofstream m(dir + "/metadata.yaml");
  m << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: " << storage << "\n  relative_file_paths:\n";
  for (const auto &f : files)
    m << "    - " << f << "\n";
  m << "  compression_format: \"" << (compression_mode.empty() ? "" : "zstd") << "\"\n  compression_mode: \""
    << compression_mode << "\"\n";
}

class Ros2Bag : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    dir_ = new ovtest::TempDir();
    folder_ = new Dataset(load_dataset(ovtest::small_folder((*dir_) / "flight", 20, 13)));
    McapExportOptions e;
    e.kalibr_files = false;
    write_mcap(*folder_, (*dir_) / "all.mcap", e);
    msgs_ = new std::vector<Msg>(messages_of((*dir_) / "all.mcap"));
  }
  static void TearDownTestSuite() {
    delete msgs_;
    delete folder_;
    delete dir_;
  }

  static void expect_like_folder(const Dataset &m) { ovtest::expect_like_folder(m, *folder_, true, 3); }
  static BagOptions calib() {
    BagOptions o;
    o.calib = {(*dir_) / "flight"};
    return o;
  }

  static ovtest::TempDir *dir_;
  static Dataset *folder_;
  static std::vector<Msg> *msgs_;
};
ovtest::TempDir *Ros2Bag::dir_ = nullptr;
Dataset *Ros2Bag::folder_ = nullptr;
std::vector<Msg> *Ros2Bag::msgs_ = nullptr;

} // namespace

TEST_F(Ros2Bag, SplitMcapFilesReadAsOne) {
  ovtest::TempDir d;
  const std::string bag = d / "rig";
  fs::create_directories(bag);
  const size_t half = msgs_->size() / 2;
  write_split_mcap(*msgs_, 0, half, bag + "/rig_0.mcap");
  write_split_mcap(*msgs_, half, msgs_->size(), bag + "/rig_1.mcap");
  write_metadata(bag, "mcap", {"rig_0.mcap", "rig_1.mcap"});
  EXPECT_TRUE(is_ros2_bag_folder(bag));
  const Dataset m = load_recording(bag + "/", calib());
  EXPECT_EQ(m.kind, "ros2bag");
  expect_like_folder(m);
  EXPECT_NE(m.notes.find("rig_0.mcap, rig_1.mcap (mcap)"), std::string::npos) << m.notes;
  // The CameraInfo and /tf_static of the first file calibrate it without --calib.
  const Dataset self = load_ros2_bag(bag);
  EXPECT_EQ(self.cam.intrinsics, folder_->cam.intrinsics);
  // A listed file that is not there.
  write_metadata(bag, "mcap", {"rig_0.mcap", "rig_2.mcap"});
  ovtest::expect_data_error([&] { load_ros2_bag(bag); }, "metadata.yaml", 0, "missing split file");
}

TEST_F(Ros2Bag, SqliteDatabaseReadAsTheFolder) {
  ovtest::TempDir d;
  for (const bool zstd : {false, true}) {
    SCOPED_TRACE(zstd);
    const std::string bag = d / (zstd ? "z" : "plain");
    fs::create_directories(bag);
    write_db3(*msgs_, bag + "/b_0.db3", zstd);
    write_metadata(bag, "sqlite3", {"b_0.db3"}, zstd ? "MESSAGE" : "");
    const Dataset m = load_ros2_bag(bag, calib());
    expect_like_folder(m);
    EXPECT_NE(m.images.front().path.find("(row "), std::string::npos) << m.images.front().path;
    EXPECT_NE(m.images.front().path.find("b_0.db3: message "), std::string::npos) << m.images.front().path;
  }
  // Not a database.
  const std::string bad = d / "bad";
  fs::create_directories(bad);
  std::ofstream(bad + "/b_0.db3") << "not sqlite";
  write_metadata(bad, "sqlite3", {"b_0.db3"});
  ovtest::expect_data_error([&] { load_ros2_bag(bad, calib()); }, "b_0.db3", 0, "not a database");
  write_metadata(bad, "sqlite3", {"b_0.db3"}, "FILE");
  ovtest::expect_data_error([&] { load_ros2_bag(bad, calib()); }, "metadata.yaml", 0, "file compression");
}

// ROS 1 bags with sensor_msgs/CompressedImage: PNG reads back as the folder; JPEG replays like the raw bag.
TEST_F(Ros2Bag, CompressedImagesInRos1Bags) {
  if (!rosbag_supported())
    GTEST_SKIP() << "built with OVTON_WITH_ROSBAG=OFF";
  ovtest::TempDir d;
  BagWriteOptions w;
  w.image_format = "png";
  w.kalibr_files = false;
  write_bag(*folder_, d / "png.bag", w);
  const Dataset b = load_bag(d / "png.bag", calib());
  expect_like_folder(b);
  EXPECT_NE(b.notes.find("/cam0/image_raw/compressed (" + std::to_string(b.images.size()) + " compressed images)"),
            std::string::npos)
      << b.notes;
  w.image_format = "jpeg";
  write_bag(*folder_, d / "jpg.bag", w);
  const Dataset j = load_bag(d / "jpg.bag", calib());
  ASSERT_EQ(j.images.size(), folder_->images.size());
  const cv::Mat x = load_image(j.images[3]), y = load_image(folder_->images[3]);
  EXPECT_LT(cv::norm(x, y, cv::NORM_L1) / static_cast<double>(x.total()), 2.0);
}

// Damaged lengths in a ROS 1 bag are named before anything is allocated for them (rosbag and roscpp would size buffers
// by them: up to 4 GiB for one field).
TEST_F(Ros2Bag, DamagedRos1LengthsNamedBeforeAllocation) {
  if (!rosbag_supported())
    GTEST_SKIP() << "built with OVTON_WITH_ROSBAG=OFF";
  ovtest::TempDir d;
  BagWriteOptions w;
  w.kalibr_files = false;
  write_bag(*folder_, d / "ok.bag", w);
  const std::string good = ovtest::bytes_of(d / "ok.bag");
  const auto damaged = [&](const std::string &name, size_t at, uint32_t value) {
    std::string b = good;
    std::memcpy(&b[at], &value, 4);
    ovtest::write_bytes(d / name, b);
    return d / name;
  };
  // The first record after the magic is the bag header: its header length.
  const std::string a = damaged("header.bag", 13, 0xfffffff0u);
  ovtest::expect_data_error([&] { load_bag(a, calib()); }, "header.bag: byte 13: the record's header runs past", 0,
                            "record length");
  // An image's pixel count (after "mono8", is_bigendian and step) inside an uncompressed chunk.
  const size_t enc = good.find("mono8");
  ASSERT_NE(enc, std::string::npos);
  const std::string b = damaged("pixels.bag", enc + 5 + 1 + 4, 0xffffff00u);
  try {
    load_bag(b, calib());
    ADD_FAILURE() << "expected a DataError";
  } catch (const DataError &e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("pixels.bag: message "), std::string::npos) << m;
    EXPECT_NE(m.find("sequence data declares 4294967040 bytes"), std::string::npos) << m;
  }
}
