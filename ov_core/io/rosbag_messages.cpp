#include "ov_core/io/rosbag_messages.h"
#include "ov_core/types/errors.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace ovton::core {

ros::Time to_ros_time(int64_t t_ns) {
  if (t_ns < 0 || t_ns / 1000000000LL > std::numeric_limits<uint32_t>::max())
    throw UsageError("stamp " + std::to_string(t_ns) + " ns cannot be a ROS 1 time (0 to 2106)");
  return ros::Time(static_cast<uint32_t>(t_ns / 1000000000LL), static_cast<uint32_t>(t_ns % 1000000000LL));
}

sensor_msgs::Image gray_to_message(const cv::Mat &gray, int64_t t_cam_ns, const std::string &frame_id) {
  if (gray.type() != CV_8UC1)
    throw UsageError("gray_to_message: expected an 8-bit single-channel image");
  sensor_msgs::Image m;
  m.header.stamp = to_ros_time(t_cam_ns);
  m.header.frame_id = frame_id;
  m.height = static_cast<uint32_t>(gray.rows);
  m.width = static_cast<uint32_t>(gray.cols);
  m.encoding = "mono8";
  m.is_bigendian = 0;
  m.step = m.width;
  m.data.resize(static_cast<size_t>(gray.rows) * gray.cols);
  for (int r = 0; r < gray.rows; ++r)
    std::memcpy(m.data.data() + static_cast<size_t>(r) * gray.cols, gray.ptr(r), gray.cols);
  return m;
}

sensor_msgs::Imu imu_to_message(const ImuData &d, const std::string &frame_id) {
  sensor_msgs::Imu m;
  m.header.stamp = to_ros_time(d.t_imu_ns);
  m.header.frame_id = frame_id;
  // No orientation estimate: REP 145 marks that with -1 in the first covariance entry.
  m.orientation_covariance[0] = -1.0;
  m.angular_velocity.x = d.wm.x();
  m.angular_velocity.y = d.wm.y();
  m.angular_velocity.z = d.wm.z();
  m.linear_acceleration.x = d.am.x();
  m.linear_acceleration.y = d.am.y();
  m.linear_acceleration.z = d.am.z();
  return m;
}

} // namespace ovton::core
