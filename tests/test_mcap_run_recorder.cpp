// A run written as Foxglove shows it through the estimator's own outputs (ovton::McapRunRecorder, `ovton run
// --mcap-out`), read back with ovton's MCAP reader: every channel's schema, count and first message against the run's
// trajectory; the file on disk while the run goes (chunks, no summary) and after an interrupt (closed whole). And a
// recording cut short: played up to the cut, its rows kept, then the cut named (ovton::play, exit 3).
#include "ov_core/io/image_codecs.h"
#include "ov_core/io/mcap_export.h"
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_msckf_ton/estimator/dataset_player.h"
#include "ov_msckf_ton/estimator/mcap_run_recorder.h"
#include "test_mcap_read_back.h"
#include "test_mcap_util.h"

#include <gtest/gtest.h>

#include <algorithm>

using namespace ovton::core;
using namespace ovtest::mcap_read_back;

namespace {

const std::string kSimConfig = std::string(OVTON_SOURCE_DIR) + "/config/sim/estimator_config.yaml";

/// One rendered flight for the tests of this file.
class McapRunRecorderTest : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    dir_ = new ovtest::TempDir();
    folder_ = new Dataset(load_dataset(ovtest::render_flight((*dir_) / "flight", 2.5, 12)));
  }
  static void TearDownTestSuite() {
    delete folder_;
    delete dir_;
  }
  static std::string flight() { return (*dir_) / "flight"; }
  /// The sim config without the coarse search, so that states come out while the images are fed.
  static ovton::msckf::VioOptions streaming_options() {
    ovton::msckf::VioOptions o = ovton::msckf::load_vio_options(kSimConfig);
    o.td.search.enabled = false;
    return o;
  }

  static ovtest::TempDir *dir_;
  static Dataset *folder_;
};
ovtest::TempDir *McapRunRecorderTest::dir_ = nullptr;
Dataset *McapRunRecorderTest::folder_ = nullptr;

int run_ovton(const std::string &args, const std::string &out) {
  return ovtest::shell(ovtest::ovton_binary() + " " + args, out);
}

} // namespace

// `ovton run --mcap-out`: one message per state on every per-state channel, the schemas Foxglove and ROS 2 name, and
// first messages that are the trajectory's first row and the image it came from.
TEST_F(McapRunRecorderTest, CliRunReadsBack) {
  ovtest::TempDir d;
  const std::string file = d / "run.mcap", err = d / "err";
  ASSERT_EQ(
      run_ovton("run -q -c " + kSimConfig + " --dataset " + flight() + " -o " + (d / "t.csv") + " --mcap-out " + file,
                err),
      0)
      << ovtest::read_text(err);
  EXPECT_NE(ovtest::read_text(err).find("run recording: " + file + " (/ovton/image "), std::string::npos)
      << ovtest::read_text(err);
  const std::vector<StateSample> traj = read_trajectory(d / "t.csv");
  ASSERT_GT(traj.size(), 20u);
  const size_t n = traj.size();
  const auto ch = read_channels(file);
  expect_run_channels(ch, n, kAny); // the path: each second and at the end
  const double span_s = ns_to_s(traj.back().t_ns - traj.front().t_ns);
  EXPECT_GE(ch.at("/ovton/path").count, static_cast<size_t>(span_s) + 1);
  EXPECT_LE(ch.at("/ovton/path").count, static_cast<size_t>(span_s) + 2);

  // The first image: the camera's stamp of a folder image, logged at the first state's IMU-clock time, JPEG.
  const Channel &img = ch.at("/ovton/image");
  EXPECT_EQ(img.first_log_time, static_cast<uint64_t>(traj.front().t_ns));
  const Ros2CompressedImage ci = decode_ros2_compressed_image(img.first.data(), img.first.size(), "f", "w");
  EXPECT_TRUE(std::any_of(folder_->images.begin(), folder_->images.end(),
                          [&](const ImageEntry &e) { return e.t_cam_ns == ci.header.stamp_ns; }));
  EXPECT_NEAR(ns_to_s(traj.front().t_ns - ci.header.stamp_ns), traj.front().td_s, 1e-6);
  EXPECT_EQ(decode_gray_image(ci.data.data, ci.data.size).size(), cv::Size(folder_->cam.width, folder_->cam.height));
  {
    const auto &b = ch.at("/ovton/features").first;
    CdrReader r(b.data(), b.size(), "f", "w");
    EXPECT_EQ(r.u32("circles"), 0u);
    ASSERT_EQ(r.u32("points"), 3u); // tracked, gated, used
    size_t points = 0;
    for (int g = 0; g < 3; ++g) {
      EXPECT_EQ(read_time(r), ci.header.stamp_ns);
      EXPECT_EQ(r.u8("type"), 1);
      const uint32_t k = r.u32("points");
      points += k;
      std::vector<double> xy(2 * k);
      r.f64_array(xy.data(), xy.size(), "xy");
      double c[4];
      r.f64_array(c, 4, "outline");
      r.u32("outline_colors");
      r.f64_array(c, 4, "fill");
      r.f64("thickness");
    }
    EXPECT_GT(points, 20u);
    ASSERT_EQ(r.u32("texts"), 1u);
    read_time(r);
    double at[2];
    r.f64_array(at, 2, "position");
    EXPECT_EQ(r.string("text").rfind("used ", 0), 0u);
  }
  {
    const auto &b = ch.at("/ovton/pose").first;
    CdrReader r(b.data(), b.size(), "f", "w");
    const PoseMsg p = read_pose(r);
    EXPECT_EQ(p.h.stamp_ns, traj.front().t_ns);
    EXPECT_LT((p.p - traj.front().p).norm(), 1e-6);
    EXPECT_LT(p.q.angularDistance(traj.front().q_WB), 1e-6);
  }
  EXPECT_NEAR(read_float64(ch.at("/ovton/td_ms").first), traj.front().td_s * 1e3, 1e-6);
  EXPECT_NEAR(read_float64(ch.at("/ovton/td_upper_ms").first) - read_float64(ch.at("/ovton/td_lower_ms").first),
              2e3 * traj.front().td_sigma_s, 1e-6);
  EXPECT_NEAR(read_float64(ch.at("/ovton/td_truth_ms").first), folder_->td_truth_at(ci.header.stamp_ns) * 1e3, 1e-9);
  {
    const auto &b = ch.at("/tf_static").first;
    const auto tf = decode_ros2_tf(b.data(), b.size(), "f", "w");
    ASSERT_EQ(tf.size(), 1u);
    EXPECT_EQ(tf[0].child, "cam");
    EXPECT_LT((tf[0].T_parent_child - folder_->imu_calib.T_BI.inverse() * folder_->cam.T_BC).norm(), 1e-9);
  }
  EXPECT_EQ(run_ovton("run -q -c " + kSimConfig + " --dataset " + flight() + " -o " + (d / "u.csv") +
                          " --mcap-images bmp --mcap-out " + (d / "x.mcap"),
                      err),
            2);
}

// An embedding program's run: the file grows in chunks while the images are fed (a killed process leaves them), and a
// run stopped early (Ctrl-C: the player's progress callback says stop) is closed whole with what it had.
TEST_F(McapRunRecorderTest, FileGrowsWithTheRunAndAnInterruptClosesIt) {
  ovtest::TempDir d;
  const std::string file = d / "run.mcap";
  ovton::EstimatorSetup setup = ovton::setup_for(*folder_, streaming_options());
  setup.threaded = false;
  ovton::Estimator est(setup);
  size_t states = 0;
  est.add_state_callback([&](const StateSample &) { ++states; });
  RunMcapOptions mo;
  mo.mcap.chunk_size = 32u << 10;
  const auto rec = ovton::McapRunRecorder::attach(est, file, mo);
  rec->set_truth(folder_->groundtruth, folder_->td_truth);
  size_t images_mid = 0, states_mid = 0;
  ovton::PlayOptions po;
  po.on_progress = [&](size_t i, size_t) {
    if (i == 25) {
      states_mid = states;
      images_mid = read_channels(file, false)["/ovton/image"].count; // the file as a killed run would leave it
    }
    return i < 35;
  };
  const ovton::PlayResult r = ovton::play(*folder_, est, po);
  EXPECT_TRUE(r.interrupted);
  rec->close();
  EXPECT_GT(images_mid, 5u);
  EXPECT_LE(images_mid, states_mid);
  const auto ch = read_channels(file);
  EXPECT_GT(states, states_mid);
  EXPECT_EQ(ch.at("/ovton/image").count, states);
  EXPECT_EQ(ch.at("/ovton/pose").count, states);
  EXPECT_EQ(ch.at("/ovton/path_truth").count, 1u);
}

// A recording cut short: `ovton run` writes the rows up to the cut, then exits 3 naming the file and the byte; the
// library's player hands out the states before throwing.
TEST_F(McapRunRecorderTest, CutRecordingKeepsItsRowsThenExits3) {
  ovtest::TempDir d;
  McapExportOptions e;
  e.mcap.chunk_size = 64u << 10;
  write_mcap(*folder_, d / "full.mcap", e);
  const std::string b = ovtest::bytes_of(d / "full.mcap");
  ovtest::write_bytes(d / "cut.mcap", b.substr(0, b.size() * 2 / 3));
  BagOptions calib;
  calib.calib = {flight()};
  const Dataset cut = load_recording(d / "cut.mcap", calib);
  ASSERT_FALSE(cut.truncated_file.empty());

  const std::string err = d / "err";
  EXPECT_EQ(run_ovton("run -q -c " + kSimConfig + " --dataset " + (d / "cut.mcap") + " --calib " + flight() + " -o " +
                          (d / "cut.csv") + " --mcap-out " + (d / "cut_run.mcap"),
                      err),
            3);
  const std::string msg = ovtest::read_text(err);
  EXPECT_NE(msg.find("cut.mcap: the record at byte "), std::string::npos) << msg;
  EXPECT_NE(msg.find("cut short"), std::string::npos) << msg;
  EXPECT_NE(msg.find("their rows are in " + (d / "cut.csv")), std::string::npos) << msg;
  const size_t rows = read_trajectory(d / "cut.csv").size();
  EXPECT_GT(rows, 10u);
  EXPECT_EQ(read_channels(d / "cut_run.mcap")["/ovton/pose"].count, rows); // the run's recording closed whole

  ovton::Estimator est(ovton::setup_for(cut, streaming_options()));
  size_t states = 0;
  est.add_state_callback([&](const StateSample &) { ++states; });
  try {
    ovton::play(cut, est);
    ADD_FAILURE() << "expected the cut to be reported";
  } catch (const DataError &x) {
    EXPECT_EQ(x.file(), d / "cut.mcap");
    EXPECT_NE(std::string(x.what()).find("the record at byte "), std::string::npos) << x.what();
  }
  EXPECT_GT(states, 10u);
}
