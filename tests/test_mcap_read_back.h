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

} // namespace ovtest::mcap_read_back
