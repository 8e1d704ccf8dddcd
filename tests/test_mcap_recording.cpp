// MCAP files as recordings: a rendered flight exported with `ovton export --format mcap` reads back as its folder
// (stamps, IMU, pixels) raw and compressed, calibrates itself from its CameraInfo and /tf_static, replays to the
// byte-identical trajectory, and damaged files are refused naming the file and the byte or the message.
#include "ov_core/io/cdr.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_store.h"
#include "ov_core/io/mcap_export.h"
#include "ov_core/io/mcap_writer.h"
#include "ov_core/io/ros2_messages.h"
#include "ov_core/io/ros2_reader.h"
#include "ov_core/io/ros2_schemas.h"
#include "ov_sim/simulator.h"
#include "test_mcap_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sys/wait.h>

namespace fs = std::filesystem;
using namespace ovton::core;

namespace {

using ovtest::bytes_of;
using ovtest::write_bytes;

/// `ovton ARGS`, its output (messages included) to `out`; the exit code.
int run_ovton(const std::string &args, const std::string &out) {
  return ovtest::shell(ovtest::ovton_binary() + " " + args, out);
}

/// A small folder and its MCAP export beside it (same stem: the folder is the file's calibration).
class McapRecording : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    dir_ = new ovtest::TempDir();
    folder_ = new Dataset(load_dataset(ovtest::small_folder((*dir_) / "flight")));
    McapExportOptions e;
    e.mcap.chunk_size = 16u << 10; // several chunks, for the cut file
    write_mcap(*folder_, (*dir_) / "flight.mcap", e);
  }
  static void TearDownTestSuite() {
    delete folder_;
    delete dir_;
  }
  static std::string mcap() { return (*dir_) / "flight.mcap"; }

  static void expect_like_folder(const Dataset &m, bool exact_pixels) {
    ovtest::expect_like_folder(m, *folder_, exact_pixels);
  }

  static ovtest::TempDir *dir_;
  static Dataset *folder_;
};
ovtest::TempDir *McapRecording::dir_ = nullptr;
Dataset *McapRecording::folder_ = nullptr;

} // namespace

TEST_F(McapRecording, ReadsBackWhatWasWritten) {
  EXPECT_TRUE(is_mcap_file(mcap()));
  const Dataset m = load_recording(mcap());
  EXPECT_EQ(m.kind, "mcap");
  expect_like_folder(m, true);
  // The companion folder (same stem) gives calibration, ground truth and td_truth.
  EXPECT_EQ(m.cam.intrinsics, folder_->cam.intrinsics);
  EXPECT_EQ(m.groundtruth.size(), folder_->groundtruth.size());
  EXPECT_EQ(m.td_truth.size(), folder_->td_truth.size());
  EXPECT_TRUE(m.truncated_file.empty());
  EXPECT_NE(m.notes.find("/cam0/image_raw (" + std::to_string(m.images.size()) + " images)"), std::string::npos)
      << m.notes;
}

TEST_F(McapRecording, CompressedImagesAndEveryChunkCompression) {
  ovtest::TempDir d;
  BagOptions o;
  o.calib = {(*dir_) / "flight"};
  for (const std::string form : {"png/lz4", "jpeg/none", "raw/unchunked"}) {
    SCOPED_TRACE(form);
    McapExportOptions e;
    e.image_format = form.substr(0, form.find('/'));
    const std::string c = form.substr(form.find('/') + 1);
    e.mcap.chunked = c != "unchunked";
    e.mcap.compression = c == "unchunked" ? "none" : c;
    e.kalibr_files = false;
    write_mcap(*folder_, d / "c.mcap", e);
    const Dataset m = load_mcap(d / "c.mcap", o);
    expect_like_folder(m, e.image_format != "jpeg");
    if (e.image_format != "raw")
      EXPECT_NE(m.notes.find("/cam0/image_raw/compressed"), std::string::npos) << m.notes;
  }
}

// Without Kalibr files or a folder beside it, the file's CameraInfo and /tf_static calibrate it.
TEST_F(McapRecording, CameraInfoAndTfStaticCalibrate) {
  ovtest::TempDir d;
  McapExportOptions e;
  e.kalibr_files = false;
  write_mcap(*folder_, d / "alone.mcap", e);
  const Dataset m = load_mcap(d / "alone.mcap");
  EXPECT_EQ(m.cam.width, folder_->cam.width);
  EXPECT_EQ(m.cam.intrinsics, folder_->cam.intrinsics);
  EXPECT_EQ(m.cam.dist_coeffs, folder_->cam.dist_coeffs);
  EXPECT_LT((m.cam.T_BC - folder_->cam.T_BC).norm(), 1e-9);
  EXPECT_NEAR(m.imu_calib.rate_hz, 200.0, 0.5);
  EXPECT_GT(m.imu_calib.gyro_noise_density, 0.0);
  EXPECT_NE(m.notes.find("CameraInfo"), std::string::npos) << m.notes;
  EXPECT_NE(m.notes.find("imu0 -> cam0"), std::string::npos) << m.notes;
  // No CameraInfo either: the error says everywhere it looked.
  McapWriter w(d / "bare.mcap");
  const uint16_t si = w.add_schema("sensor_msgs/msg/Image", "ros2msg", ros2_schema("sensor_msgs/msg/Image"));
  const uint16_t su = w.add_schema("sensor_msgs/msg/Imu", "ros2msg", ros2_schema("sensor_msgs/msg/Imu"));
  const uint16_t ci = w.add_channel("/cam0/image_raw", si, "cdr"), cu = w.add_channel("/imu0", su, "cdr");
  w.write(ci, 10, encode_ros2_image(cv::Mat(480, 752, CV_8UC1, cv::Scalar(7)), 10, "cam0"));
  for (int k = 0; k < 3; ++k) {
    ImuData u;
    u.t_imu_ns = 5 * k;
    w.write(cu, u.t_imu_ns, encode_ros2_imu(u, "imu0"));
  }
  w.close();
  ovtest::expect_data_error([&] { load_mcap(d / "bare.mcap"); }, "bare.mcap", 0, "no calibration");
  try {
    load_mcap(d / "bare.mcap");
  } catch (const DataError &e) {
    EXPECT_NE(std::string(e.what()).find("sensor_msgs/msg/CameraInfo topic (/cam0/camera_info)"), std::string::npos)
        << e.what();
  }
}

// A recorder that crashed: the file ends inside a chunk, without summary or footer. What precedes the cut is replayed,
// then the player names the file and the byte (a run keeps its rows up to there).
TEST_F(McapRecording, CutFileReplaysUpToTheCut) {
  ovtest::TempDir d;
  const std::string b = bytes_of(mcap());
  write_bytes(d / "cut.mcap", b.substr(0, b.size() * 2 / 3));
  BagOptions o;
  o.calib = {(*dir_) / "flight"};
  const Dataset m = load_mcap(d / "cut.mcap", o);
  EXPECT_GT(m.images.size(), folder_->images.size() / 3);
  EXPECT_LT(m.images.size(), folder_->images.size());
  EXPECT_EQ(m.truncated_file, d / "cut.mcap");
  EXPECT_NE(m.notes.find("TRUNCATED"), std::string::npos) << m.notes;
  // What a player reports after feeding the images before the cut (ovton::play calls it after its last image).
  try {
    check_not_truncated(m);
    ADD_FAILURE() << "expected the cut to be reported";
  } catch (const DataError &e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("cut.mcap: the record at byte "), std::string::npos) << msg;
    EXPECT_NE(msg.find("cut short"), std::string::npos) << msg;
  }
  EXPECT_NO_THROW(check_not_truncated(*folder_));
}

TEST_F(McapRecording, DamageNamesTheFileAndPlace) {
  ovtest::TempDir d;
  BagOptions o;
  o.calib = {(*dir_) / "flight"};
  // A corrupt chunk (raw images in uncompressed chunks: the CRC finds it).
  McapExportOptions e;
  e.mcap.compression = "none";
  e.kalibr_files = false;
  write_mcap(*folder_, d / "n.mcap", e);
  std::string b = bytes_of(d / "n.mcap");
  b[b.size() / 2] = static_cast<char>(b[b.size() / 2] ^ 1);
  write_bytes(d / "crc.mcap", b);
  try {
    load_mcap(d / "crc.mcap", o);
    ADD_FAILURE() << "expected a CRC error";
  } catch (const DataError &err) {
    EXPECT_NE(std::string(err.what()).find("crc.mcap: chunk at byte "), std::string::npos) << err.what();
  }
  // An unsupported image encoding, named by message and chunk.
  {
    McapWriter w(d / "yuv.mcap");
    const uint16_t si = w.add_schema("sensor_msgs/msg/Image", "ros2msg", ros2_schema("sensor_msgs/msg/Image"));
    const uint16_t su = w.add_schema("sensor_msgs/msg/Imu", "ros2msg", ros2_schema("sensor_msgs/msg/Imu"));
    const uint16_t ci = w.add_channel("/cam0/image_raw", si, "cdr"), cu = w.add_channel("/imu0", su, "cdr");
    for (int k = 0; k < 3; ++k) {
      ImuData u;
      u.t_imu_ns = 5 * k;
      w.write(cu, u.t_imu_ns, encode_ros2_imu(u, "imu0"));
    }
    CdrWriter m;
    write_ros2_header(m, 7, "cam0");
    m.u32(480);
    m.u32(752);
    m.string("yuv422");
    m.u8(0);
    m.u32(752 * 2);
    const std::vector<uint8_t> px(752 * 2 * 480, 0);
    m.seq_bytes(px.data(), px.size());
    w.write(ci, 7, m.take());
    w.close();
  }
  try {
    load_mcap(d / "yuv.mcap", o);
    ADD_FAILURE() << "expected an error";
  } catch (const DataError &err) {
    const std::string m = err.what();
    EXPECT_NE(m.find("yuv.mcap: message 3 (/cam0/image_raw) in the chunk at byte "), std::string::npos) << m;
    EXPECT_NE(m.find("unsupported image encoding 'yuv422'"), std::string::npos) << m;
  }
  // Topics: a missing one, one of another type, one with no messages, one in another message encoding.
  McapWriter w(d / "topics.mcap");
  const uint16_t si = w.add_schema("sensor_msgs/msg/Image", "ros2msg", ros2_schema("sensor_msgs/msg/Image"));
  const uint16_t su = w.add_schema("sensor_msgs/msg/Imu", "ros2msg", ros2_schema("sensor_msgs/msg/Imu"));
  w.add_channel("/cam0/image_raw", si, "cdr");
  const uint16_t json = w.add_channel("/json/image", si, "json");
  const uint16_t cu = w.add_channel("/imu0", su, "cdr");
  w.write(json, 1, std::vector<uint8_t>{'{', '}'});
  for (int k = 0; k < 3; ++k) {
    ImuData u;
    u.t_imu_ns = 5 * k;
    w.write(cu, u.t_imu_ns, encode_ros2_imu(u, "imu0"));
  }
  w.close();
  const auto expect = [&](const std::string &cam_topic, const std::string &text) {
    BagOptions t = o;
    t.cam_topic = cam_topic;
    try {
      load_mcap(d / "topics.mcap", t);
      ADD_FAILURE() << "expected an error for " << cam_topic;
    } catch (const DataError &err) {
      EXPECT_NE(std::string(err.what()).find(text), std::string::npos) << err.what();
    }
  };
  expect("/nope", "no topic /nope in the recording (topics: /cam0/image_raw [sensor_msgs/msg/Image]");
  expect("/imu0", "topic /imu0 holds sensor_msgs/msg/Imu, not sensor_msgs/msg/Image");
  expect("/cam0/image_raw", "topic /cam0/image_raw has no messages");
  expect("/json/image", "topic /json/image is recorded in the message encoding 'json'");
}

// The user's path: `ovton run` on a rendered folder and on its MCAP export.
TEST(McapRun, ReplaysToTheByteIdenticalTrajectory) {
  ovtest::TempDir d;
  const Dataset folder = load_dataset(ovtest::render_flight(d / "flight", 2.5, 12));
  write_mcap(folder, d / "flight.mcap");
  const std::string cfg = std::string(OVTON_SOURCE_DIR) + "/config/sim/estimator_config.yaml", err = d / "e";
  const std::string common = "run -q -c " + cfg + " ";
  ASSERT_EQ(run_ovton(common + "--dataset " + (d / "flight") + " -o " + (d / "f.csv"), err), 0)
      << ovtest::read_text(err);
  ASSERT_EQ(run_ovton(common + "--dataset " + (d / "flight.mcap") + " -o " + (d / "m.csv"), err), 0)
      << ovtest::read_text(err);
  const std::string a = bytes_of(d / "f.csv"), b = bytes_of(d / "m.csv");
  EXPECT_GT(std::count(a.begin(), a.end(), '\n'), 40);
  EXPECT_TRUE(a == b) << "trajectories differ";
  EXPECT_EQ(run_ovton("info --dataset " + (d / "flight.mcap") + " --cam-topic /nope", err), 3);
  EXPECT_NE(ovtest::read_text(err).find("no topic /nope"), std::string::npos) << ovtest::read_text(err);
}
