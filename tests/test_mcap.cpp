// MCAP and CDR at the format level, on files the tests write: records and chunks read back in every compression, with
// and without a summary; damaged files (a chunk whose CRC fails, a cut) named by file and byte; CDR messages read back
// as written and refused when short or of an unknown encapsulation.
#include "ov_core/io/cdr.h"
#include "ov_core/io/mcap_format.h"
#include "ov_core/io/mcap_reader.h"
#include "ov_core/io/mcap_writer.h"
#include "ov_core/io/ros2_messages.h"
#include "ov_core/io/ros2_schemas.h"
#include "test_mcap_util.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <fstream>
#include <numeric>

using namespace ovton::core;

namespace {

using ovtest::bytes_of;
using ovtest::write_bytes;

/// Message i of a test file: its index in its first bytes, then a pattern (some messages large enough to span chunks).
std::vector<uint8_t> payload(size_t i) {
  std::vector<uint8_t> p(i % 7 == 0 ? 70000 : 40 + i % 13);
  std::iota(p.begin(), p.end(), static_cast<uint8_t>(i));
  std::memcpy(p.data(), &i, sizeof i);
  return p;
}

constexpr size_t kMessages = 300;

/// Writes kMessages messages on two channels.
void write_test_file(const std::string &path, const McapWriteOptions &o) {
  McapWriter w(path, o);
  const uint16_t s = w.add_schema("test_msgs/msg/Blob", "ros2msg", "uint8[] data\n");
  const uint16_t a = w.add_channel("/a", s, "cdr"), b = w.add_channel("/b", s, "cdr", {{"k", "v"}});
  for (size_t i = 0; i < kMessages; ++i)
    w.write(i % 3 ? a : b, 1000 + i, payload(i));
  w.close();
}

struct ReadBack {
  std::vector<McapChannel> channels;
  std::vector<McapMessage> messages; ///< data pointers cleared: they live during the callback only
  std::vector<std::vector<uint8_t>> data;
  McapScan scan;
};

ReadBack read_back(McapReader &r) {
  ReadBack out;
  out.scan = r.scan([&](const McapChannel &c) { out.channels.push_back(c); },
                    [&](const McapMessage &m) {
                      out.data.emplace_back(m.data, m.data + m.size);
                      out.messages.push_back(m);
                      out.messages.back().data = nullptr;
                    });
  return out;
}

} // namespace

TEST(Mcap, RecordsReadBackInEveryForm) {
  ovtest::TempDir d;
  struct Form {
    const char *name;
    McapWriteOptions o;
  };
  std::vector<Form> forms(5);
  forms[0] = {"zstd", {}};
  forms[1] = {"lz4", {}};
  forms[1].o.compression = "lz4";
  forms[2] = {"none", {}};
  forms[2].o.compression = "none";
  forms[3] = {"no summary, small chunks", {}};
  forms[3].o.summary = false;
  forms[3].o.chunk_size = 5000;
  forms[4] = {"unchunked", {}};
  forms[4].o.chunked = false;
  forms[4].o.compression = "none";
  for (const Form &f : forms) {
    SCOPED_TRACE(f.name);
    const std::string file = d / "t.mcap";
    write_test_file(file, f.o);
    McapReader r(file);
    EXPECT_EQ(r.profile(), "ros2");
    const ReadBack rb = read_back(r);
    EXPECT_TRUE(rb.scan.complete) << rb.scan.cut_reason;
    ASSERT_EQ(rb.channels.size(), 2u);
    EXPECT_EQ(rb.channels[1].topic, "/b");
    EXPECT_EQ(rb.channels[1].schema_name, "test_msgs/msg/Blob");
    EXPECT_EQ(rb.channels[1].metadata.at("k"), "v");
    ASSERT_EQ(rb.messages.size(), kMessages);
    EXPECT_EQ(rb.scan.chunks > 0, f.o.chunked);
    for (size_t i = 0; i < kMessages; i += 1) {
      ASSERT_EQ(rb.data[i], payload(i)) << "message " << i;
      EXPECT_EQ(rb.messages[i].log_time, 1000 + i);
      EXPECT_EQ(rb.messages[i].channel_id, i % 3 ? 0 : 1);
    }
    // Fetched again, out of order (another chunk each time), as a replay's prefetcher may ask.
    for (size_t i : {size_t{299}, size_t{0}, size_t{150}, size_t{151}, size_t{7}})
      EXPECT_EQ(r.fetch(rb.messages[i].ref), payload(i)) << "fetch " << i;
  }
}

TEST(Mcap, CorruptChunkNamesTheByte) {
  ovtest::TempDir d;
  // Uncompressed chunks: a flipped byte in the records is found by the chunk's CRC.
  McapWriteOptions none;
  none.compression = "none";
  write_test_file(d / "n.mcap", none);
  std::string b = bytes_of(d / "n.mcap");
  b[b.size() / 3] = static_cast<char>(b[b.size() / 3] ^ 0x5a);
  write_bytes(d / "bad.mcap", b);
  McapReader r(d / "bad.mcap");
  try {
    read_back(r);
    ADD_FAILURE() << "expected a CRC error";
  } catch (const DataError &e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("bad.mcap: chunk at byte "), std::string::npos) << m;
    EXPECT_NE(m.find("CRC mismatch"), std::string::npos) << m;
  }
  // A damaged zstd stream is named the same way (by the decompressor or the CRC).
  write_test_file(d / "t.mcap", McapWriteOptions());
  b = bytes_of(d / "t.mcap");
  b[b.size() / 3] = static_cast<char>(b[b.size() / 3] ^ 0x5a);
  write_bytes(d / "badz.mcap", b);
  McapReader rz(d / "badz.mcap");
  ovtest::expect_data_error([&] { read_back(rz); }, "badz.mcap: chunk at byte ", 0, "damaged zstd chunk");
}

TEST(Mcap, CutFileKeepsWhatPrecedesTheCut) {
  ovtest::TempDir d;
  McapWriteOptions o;
  o.chunk_size = 20000;
  write_test_file(d / "t.mcap", o);
  const std::string b = bytes_of(d / "t.mcap");
  // Cut inside the data section: the walk stops at the last complete record and says where.
  for (size_t cut : {b.size() / 2, b.size() / 5}) {
    SCOPED_TRACE(cut);
    write_bytes(d / "cut.mcap", b.substr(0, cut));
    McapReader r(d / "cut.mcap");
    const ReadBack rb = read_back(r);
    EXPECT_FALSE(rb.scan.complete);
    EXPECT_LE(rb.scan.cut_offset, cut);
    EXPECT_NE(rb.scan.cut_reason.find("byte"), std::string::npos) << rb.scan.cut_reason;
    EXPECT_GT(rb.messages.size(), cut == b.size() / 2 ? kMessages / 4 : 0);
    EXPECT_LT(rb.messages.size(), kMessages);
    for (size_t i = 0; i < rb.messages.size(); ++i)
      ASSERT_EQ(rb.data[i], payload(i));
  }
  // Cut after the Data End record (summary or footer lost): every message is there.
  write_bytes(d / "cut.mcap", b.substr(0, b.size() - 40));
  McapReader whole(d / "cut.mcap");
  const ReadBack rb = read_back(whole);
  EXPECT_TRUE(rb.scan.complete);
  EXPECT_EQ(rb.messages.size(), kMessages);
  // Cut inside the header record: nothing to read.
  write_bytes(d / "cut.mcap", b.substr(0, 20));
  ovtest::expect_data_error([&] { McapReader r(d / "cut.mcap"); }, "cut.mcap: byte 8", 0, "cut header");
  // Not an MCAP file at all.
  write_bytes(d / "text.mcap", "hello\n");
  ovtest::expect_data_error([&] { McapReader r(d / "text.mcap"); }, "text.mcap", 0, "not an MCAP file");
}

TEST(Cdr, MessagesReadBackAsWritten) {
  ImuData u;
  u.t_imu_ns = 1403715285262142976;
  u.wm = {0.1, -0.2, 0.3};
  u.am = {9.7, 0.01, -0.5};
  std::vector<uint8_t> m = encode_ros2_imu(u, "imu0");
  std::string frame;
  const ImuData v = decode_ros2_imu(m.data(), m.size(), "f", "w", &frame);
  EXPECT_EQ(v.t_imu_ns, u.t_imu_ns);
  EXPECT_EQ(v.wm, u.wm);
  EXPECT_EQ(v.am, u.am);
  EXPECT_EQ(frame, "imu0");
  // One byte short: refused, naming the field.
  try {
    decode_ros2_imu(m.data(), m.size() - 1, "f.mcap", "message 3 (/imu0)");
    ADD_FAILURE() << "expected a truncation error";
  } catch (const DataError &e) {
    EXPECT_NE(std::string(e.what()).find("f.mcap: message 3 (/imu0): message ends at byte"), std::string::npos)
        << e.what();
  }
  // An encapsulation ovton does not read (parameter list).
  m[1] = 3;
  ovtest::expect_data_error([&] { decode_ros2_imu(m.data(), m.size(), "f.mcap", "w"); }, "f.mcap", 0, "encapsulation");

  cv::Mat gray(4, 6, CV_8UC1);
  std::iota(gray.data, gray.data + gray.total(), 0);
  const auto im = encode_ros2_image(gray, -5, "cam0"); // a negative stamp: seconds -1, nanoseconds 999999995
  const Ros2Image ri = decode_ros2_image(im.data(), im.size(), "f", "w");
  EXPECT_EQ(ri.header.stamp_ns, -5);
  EXPECT_EQ(ri.pixels.encoding, "mono8");
  EXPECT_EQ(cv::countNonZero(raw_image_to_gray(ri.pixels, "f", "w") != gray), 0);
  // mono16 of the same pixels, widened as v << 8 and as v * 257 (full range), little- and big-endian, at an odd
  // address: each gives back the mono8 pixels exactly (a rounding 1/256 scale turns v * 257 into v + 1 for v >= 128).
  cv::Mat wide(1, 256, CV_8UC1);
  std::iota(wide.data, wide.data + wide.total(), 0);
  for (const int factor : {256, 257})
    for (const bool big : {false, true}) {
      std::vector<uint8_t> bytes(1 + 2 * 256);
      for (int v = 0; v < 256; ++v) {
        const int w = v * factor;
        bytes[1 + 2 * v + (big ? 0 : 1)] = static_cast<uint8_t>(w >> 8);
        bytes[1 + 2 * v + (big ? 1 : 0)] = static_cast<uint8_t>(w & 0xff);
      }
      RawImageView m16;
      m16.width = 256;
      m16.height = 1;
      m16.step = 512;
      m16.encoding = "mono16";
      m16.big_endian = big;
      m16.data = bytes.data() + 1;
      m16.size = 512;
      EXPECT_EQ(cv::countNonZero(raw_image_to_gray(m16, "f", "w") != wide), 0)
          << "mono16 as v * " << factor << (big ? ", big-endian" : ", little-endian");
    }
  // Only the first bytes given: header and size read, the pixels' place known, the bytes not there.
  const Ros2Image head = decode_ros2_image(im.data(), 56, "f", "w", im.size());
  EXPECT_EQ(head.pixels.width, 6u);
  EXPECT_EQ(head.pixels.size, 24u);
  EXPECT_EQ(head.pixels.data, nullptr);

  CameraCalib cam;
  cam.width = 752;
  cam.height = 480;
  cam.intrinsics << 458.654, 457.296, 367.215, 248.375;
  cam.dist_coeffs << -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05;
  const auto ci = encode_ros2_camera_info(cam, 7, "cam0");
  const Ros2CameraInfo info = decode_ros2_camera_info(ci.data(), ci.size(), "f", "w");
  const CameraCalib back = camera_from_info(info, Eigen::Matrix4d::Identity(), "f", "w");
  EXPECT_EQ(back.intrinsics, cam.intrinsics);
  EXPECT_EQ(back.dist_coeffs, cam.dist_coeffs);
  EXPECT_EQ(info.distortion_model, "plumb_bob");

  Ros2Transform t;
  t.parent = "imu0";
  t.child = "cam0";
  t.T_parent_child.topLeftCorner<3, 3>() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  t.T_parent_child.topRightCorner<3, 1>() << 0.1, -0.2, 0.05;
  const auto tf = encode_ros2_tf({t, t});
  const auto tb = decode_ros2_tf(tf.data(), tf.size(), "f", "w");
  ASSERT_EQ(tb.size(), 2u);
  EXPECT_EQ(tb[1].child, "cam0");
  EXPECT_LT((tb[1].T_parent_child - t.T_parent_child).norm(), 1e-12);
}

// A big-endian plain-CDR message (some DDS vendors write it) reads the same: built by hand, fields aligned from the
// end of the encapsulation header.
TEST(Cdr, BigEndianAndAlignment) {
  const std::vector<uint8_t> m = {0x00, 0x00, 0x00, 0x00,                   // CDR_BE
                                  0x00, 0x00, 0x00, 0x05,                   // u32 5
                                  0x00, 0x00, 0x00, 0x02, 'a', 0x00,        // string "a"
                                  0x07, 0x00,                               // u8 7, padding to 8
                                  0x3f, 0xf8, 0,    0,    0,   0,    0, 0}; // f64 1.5 at offset 16 (12 from the header)
  CdrReader r(m.data(), m.size(), "f", "w");
  EXPECT_EQ(r.u32("a"), 5u);
  EXPECT_EQ(r.string("b"), "a");
  EXPECT_EQ(r.u8("c"), 7);
  EXPECT_THROW(r.f64("d"), DataError); // 8-byte alignment from the header puts it at 20: past the end
  const std::vector<uint8_t> m2 = {0x00, 0x00, 0x00, 0x00, 0x07, 0, 0, 0, 0, 0, 0, 0, 0x3f, 0xf8, 0, 0, 0, 0, 0, 0};
  CdrReader r2(m2.data(), m2.size(), "f", "w");
  EXPECT_EQ(r2.u8("c"), 7);
  EXPECT_EQ(r2.f64("d"), 1.5);
}

TEST(Ros2Schemas, EveryWrittenTypeHasItsDependencies) {
  const std::string image = ros2_schema("sensor_msgs/msg/Image");
  EXPECT_EQ(image.rfind("std_msgs/Header header\n", 0), 0u) << image;
  EXPECT_NE(image.find("\nMSG: std_msgs/Header\n"), std::string::npos);
  EXPECT_NE(image.find("\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"), std::string::npos);
  const std::string ann = ros2_schema("foxglove_msgs/msg/ImageAnnotations");
  for (const char *dep :
       {"foxglove_msgs/CircleAnnotation", "foxglove_msgs/PointsAnnotation", "foxglove_msgs/TextAnnotation",
        "foxglove_msgs/Point2", "foxglove_msgs/Color", "builtin_interfaces/Time"})
    EXPECT_NE(ann.find(std::string(80, '=') + "\nMSG: " + dep + "\n"), std::string::npos) << dep;
  for (const char *t :
       {"sensor_msgs/msg/CompressedImage", "sensor_msgs/msg/Imu", "sensor_msgs/msg/CameraInfo",
        "tf2_msgs/msg/TFMessage", "nav_msgs/msg/Path", "geometry_msgs/msg/PoseStamped", "std_msgs/msg/Float64"})
    EXPECT_FALSE(ros2_schema(t).empty()) << t;
  EXPECT_THROW(ros2_schema("foo_msgs/msg/Bar"), UsageError);
}
