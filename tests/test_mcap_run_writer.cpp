// The run as Foxglove shows it (RunMcapWriter, for `ovton run --mcap-out`): a synthetic run written through the writer
// and read back with ovton's own MCAP reader: every channel, its schema's ROS 2 / Foxglove name, its message count and
// its first message.
#include "ov_core/io/cdr.h"
#include "ov_core/io/image_codecs.h"
#include "ov_core/io/mcap_format.h"
#include "ov_core/io/mcap_reader.h"
#include "ov_core/io/ros2_messages.h"
#include "ov_core/io/run_mcap_writer.h"
#include "test_mcap_read_back.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <fstream>
#include <map>

using namespace ovton::core;
using namespace ovtest::mcap_read_back;

TEST(RunMcapWriter, SyntheticRunReadsBack) {
  ovtest::TempDir d;
  const std::string file = d / "run.mcap";
  const int64_t t0 = 1403715285262142976;
  const int64_t td_ns = 4000000; // t_imu = t_cam + 4 ms
  const int images = 30;         // 1.5 s at 20 Hz
  std::vector<StateSample> gt;
  for (int k = -10; k <= 200; ++k) { // 100 Hz truth around the run
    StateSample g;
    g.t_ns = t0 + td_ns + k * 10000000LL;
    g.p = Eigen::Vector3d(0.01 * k, 1.0, -0.5);
    g.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(0.002 * k, Eigen::Vector3d::UnitZ()));
    gt.push_back(g);
  }
  std::vector<TdSample> td_truth = {{t0, 0.004}, {t0 + 10000000000LL, 0.005}};
  RunMcapOptions o;
  o.T_BC = Eigen::Matrix4d::Identity();
  {
    RunMcapWriter w(file, o);
    w.set_truth(gt, td_truth);
    cv::Mat gray(48, 64, CV_8UC1);
    cv::randu(gray, 0, 255);
    for (int i = 0; i < images; ++i) {
      const int64_t t_cam = t0 + i * 50000000LL;
      std::vector<RunFeature> f;
      for (size_t id = 0; id < 12; ++id)
        f.push_back({id, Eigen::Vector2d(3.0 * id, 2.0 * id + i),
                     id < 6   ? FeatureStatus::Used
                     : id < 8 ? FeatureStatus::Gated
                              : FeatureStatus::Tracked});
      w.add_image(t_cam, t_cam + td_ns, gray, f);
      StateSample s;
      s.t_ns = t_cam + td_ns;
      s.p = Eigen::Vector3d(0.01 * i, 1.0, -0.5);
      s.has_td = true;
      s.td_s = 0.0041;
      s.td_sigma_s = 0.0005;
      w.add_state(s);
    }
    w.close();
    const auto counts = w.message_counts();
    EXPECT_EQ(counts.size(), 12u);
  }

  const auto ch = read_channels(file);
  expect_run_channels(ch, images, 3); // the path: the first state, once 1 s later, the end

  // First messages. The image: JPEG stamped with the camera's clock, logged at the IMU clock.
  const Channel &img = ch.at("/ovton/image");
  EXPECT_EQ(img.first_log_time, static_cast<uint64_t>(t0 + td_ns));
  const Ros2CompressedImage ci = decode_ros2_compressed_image(img.first.data(), img.first.size(), "f", "w");
  EXPECT_EQ(ci.header.stamp_ns, t0);
  EXPECT_EQ(ci.format, "jpeg");
  EXPECT_EQ(decode_gray_image(ci.data.data, ci.data.size).size(), cv::Size(64, 48));
  // The annotations: tracked, gated, used, with their counts in the label.
  {
    const auto &b = ch.at("/ovton/features").first;
    CdrReader r(b.data(), b.size(), "f", "w");
    EXPECT_EQ(r.u32("circles"), 0u);
    ASSERT_EQ(r.u32("points"), 3u);
    const size_t want[3] = {4, 2, 6};
    for (size_t g = 0; g < 3; ++g) {
      EXPECT_EQ(read_time(r), t0);
      EXPECT_EQ(r.u8("type"), 1);
      const uint32_t n = r.u32("points");
      EXPECT_EQ(n, want[g]);
      std::vector<double> xy(2 * n);
      r.f64_array(xy.data(), xy.size(), "xy");
      double c[4];
      r.f64_array(c, 4, "outline");
      EXPECT_EQ(r.u32("outline_colors"), 0u);
      r.f64_array(c, 4, "fill");
      r.f64("thickness");
    }
    ASSERT_EQ(r.u32("texts"), 1u);
    read_time(r);
    double at[2];
    r.f64_array(at, 2, "position");
    EXPECT_EQ(r.string("text"), "used 6  gated 2  tracked 4");
  }
  {
    const auto &b = ch.at("/ovton/pose").first;
    CdrReader r(b.data(), b.size(), "f", "w");
    const PoseMsg p = read_pose(r);
    EXPECT_EQ(p.h.stamp_ns, t0 + td_ns);
    EXPECT_EQ(p.h.frame_id, "world");
    EXPECT_EQ(p.p, Eigen::Vector3d(0.0, 1.0, -0.5));
  }
  {
    const auto &b = ch.at("/ovton/pose_truth").first;
    CdrReader r(b.data(), b.size(), "f", "w");
    const PoseMsg p = read_pose(r);
    EXPECT_LT((p.p - gt[10].p).norm(), 1e-12); // the truth sample at the first state's time
  }
  {
    const auto &b = ch.at("/tf").first;
    const auto tf = decode_ros2_tf(b.data(), b.size(), "f", "w");
    ASSERT_EQ(tf.size(), 2u);
    EXPECT_EQ(tf[0].parent, "world");
    EXPECT_EQ(tf[0].child, "imu");
    EXPECT_EQ(tf[1].child, "imu_truth");
  }
  {
    const auto &b = ch.at("/ovton/path_truth").first;
    CdrReader r(b.data(), b.size(), "f", "w");
    read_time(r);
    r.string("frame");
    EXPECT_EQ(r.u32("poses"), 201u); // the truth samples from the first state on
  }
  EXPECT_DOUBLE_EQ(read_float64(ch.at("/ovton/td_ms").first), 4.1);
  EXPECT_DOUBLE_EQ(read_float64(ch.at("/ovton/td_lower_ms").first), 3.6);
  EXPECT_DOUBLE_EQ(read_float64(ch.at("/ovton/td_upper_ms").first), 4.6);
  EXPECT_DOUBLE_EQ(read_float64(ch.at("/ovton/td_truth_ms").first), 4.0);

  // An indexed file: the footer points at a summary (Foxglove seeks with it).
  std::ifstream in(file, std::ios::binary);
  in.seekg(-(8 + 20), std::ios::end);
  uint8_t footer[8];
  in.read(reinterpret_cast<char *>(footer), 8);
  EXPECT_GT(mcap::get_u64(footer), 0u);
}

// A run stopped by an error: the writer's destructor still leaves a whole, indexed file.
TEST(RunMcapWriter, DestructorFinishesTheFile) {
  ovtest::TempDir d;
  {
    RunMcapOptions o;
    o.image_format = "raw";
    RunMcapWriter w(d / "r.mcap", o);
    w.add_image(10, 11, cv::Mat(8, 8, CV_8UC1, cv::Scalar(3)), {});
    w.add_image(60, 61, cv::Mat(), {{4, Eigen::Vector2d(1, 2), FeatureStatus::Used}}); // feature-level: no pixels
    StateSample s;
    s.t_ns = 11;
    w.add_state(s);
  }
  const auto ch = read_channels(d / "r.mcap");
  EXPECT_EQ(ch.at("/ovton/image").type, "sensor_msgs/msg/Image");
  EXPECT_EQ(ch.at("/ovton/image").count, 1u);
  EXPECT_EQ(ch.at("/ovton/features").count, 2u);
  EXPECT_EQ(ch.at("/ovton/pose").count, 1u);
  EXPECT_EQ(ch.at("/ovton/pose_truth").count, 0u);
  EXPECT_EQ(ch.at("/ovton/td_ms").count, 0u); // the state had no t_d
  EXPECT_THROW(RunMcapWriter(d / "x.mcap",
                             [] {
                               RunMcapOptions o;
                               o.image_format = "bmp";
                               return o;
                             }()),
               UsageError);
}
