#pragma once
// Reading back what RunMcapWriter wrote (tests of `ovton run --mcap-out`): each channel's schema name, message count
// and first message through ovton's own MCAP reader, and the few ROS 2 messages the tests look into.
#include "ov_core/io/cdr.h"
#include "ov_core/io/mcap_reader.h"
#include "ov_core/io/ros2_messages.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <map>
#include <string>
#include <vector>

namespace ovtest::mcap_read_back {

using ovton::core::CdrReader;

struct Channel {
  std::string type;
  size_t count = 0;
  std::vector<uint8_t> first;
  uint64_t first_log_time = 0;
};

/// Every channel by topic; expects a complete file (summary and footer) unless `complete` is false.
inline std::map<std::string, Channel> read_channels(const std::string &file, bool complete = true) {
  ovton::core::McapReader r(file);
  std::map<uint16_t, std::string> topic;
  std::map<std::string, Channel> out;
  const ovton::core::McapScan s = r.scan(
      [&](const ovton::core::McapChannel &c) {
        topic[c.id] = c.topic;
        out[c.topic].type = c.schema_name;
        EXPECT_EQ(c.message_encoding, "cdr") << c.topic;
        EXPECT_EQ(c.schema_encoding, "ros2msg") << c.topic;
      },
      [&](const ovton::core::McapMessage &m) {
        Channel &c = out[topic[m.channel_id]];
        if (c.count++ == 0) {
          c.first.assign(m.data, m.data + m.size);
          c.first_log_time = m.log_time;
        }
      });
  EXPECT_EQ(s.complete, complete) << file;
  return out;
}

struct PoseMsg {
  ovton::core::Ros2Header h;
  Eigen::Vector3d p;
  Eigen::Quaterniond q;
};

inline int64_t read_time(CdrReader &r) {
  const int32_t s = r.i32("sec");
  return s * 1000000000LL + r.u32("nsec");
}

inline PoseMsg read_pose(CdrReader &r) {
  PoseMsg m;
  m.h.stamp_ns = read_time(r);
  m.h.frame_id = r.string("frame");
  r.f64_array(m.p.data(), 3, "p");
  double q[4];
  r.f64_array(q, 4, "q");
  m.q = Eigen::Quaterniond(q[3], q[0], q[1], q[2]);
  return m;
}

inline double read_float64(const std::vector<uint8_t> &b) {
  CdrReader r(b.data(), b.size(), "f", "w");
  return r.f64("data");
}

/// A run's file (RunMcapWriter, JPEG images) holds its 12 channels with their Foxglove / ROS 2 schema names:
/// `per_image` messages on every channel written per image or state, `paths` on /ovton/path (kAny: not checked), one
/// /tf_static and one /ovton/path_truth.
constexpr size_t kAny = static_cast<size_t>(-1);
inline void expect_run_channels(const std::map<std::string, Channel> &ch, size_t per_image, size_t paths) {
  const std::map<std::string, std::pair<std::string, size_t>> expected = {
      {"/ovton/image", {"sensor_msgs/msg/CompressedImage", per_image}},
      {"/ovton/features", {"foxglove_msgs/msg/ImageAnnotations", per_image}},
      {"/ovton/pose", {"geometry_msgs/msg/PoseStamped", per_image}},
      {"/ovton/pose_truth", {"geometry_msgs/msg/PoseStamped", per_image}},
      {"/tf", {"tf2_msgs/msg/TFMessage", per_image}},
      {"/tf_static", {"tf2_msgs/msg/TFMessage", 1}},
      {"/ovton/path", {"nav_msgs/msg/Path", paths}},
      {"/ovton/path_truth", {"nav_msgs/msg/Path", 1}},
      {"/ovton/td_ms", {"std_msgs/msg/Float64", per_image}},
      {"/ovton/td_lower_ms", {"std_msgs/msg/Float64", per_image}},
      {"/ovton/td_upper_ms", {"std_msgs/msg/Float64", per_image}},
      {"/ovton/td_truth_ms", {"std_msgs/msg/Float64", per_image}},
  };
  ASSERT_EQ(ch.size(), expected.size());
  for (const auto &[topic, e] : expected) {
    ASSERT_TRUE(ch.count(topic)) << topic;
    EXPECT_EQ(ch.at(topic).type, e.first) << topic;
    if (e.second != kAny) {
      EXPECT_EQ(ch.at(topic).count, e.second) << topic;
    }
  }
}

} // namespace ovtest::mcap_read_back
