#include "ov_core/io/rosbag_messages.h"
#include "ov_core/io/image_message.h"
#include "ov_core/io/recording_topics.h"
#include "ov_core/types/errors.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace ovton::core {

namespace {

RawImageView view_of(const sensor_msgs::Image &m) {
  RawImageView v;
  v.width = m.width;
  v.height = m.height;
  v.step = m.step;
  v.encoding = m.encoding;
  v.big_endian = m.is_bigendian != 0;
  v.data = m.data.data();
  v.size = m.data.size();
  return v;
}

} // namespace

void check_image_message(const sensor_msgs::Image &m, int width, int height, const std::string &file,
                         const std::string &where) {
  check_raw_image(view_of(m), width, height, file, where);
}

cv::Mat image_to_gray(const sensor_msgs::Image &m, const std::string &file, const std::string &where) {
  return raw_image_to_gray(view_of(m), file, where);
}

void check_image_message(const sensor_msgs::CompressedImage &m, int width, int height, const std::string &file,
                         const std::string &where) {
  check_compressed_image(m.format, m.data.data(), m.data.size(), width, height, file, where);
}

cv::Mat image_to_gray(const sensor_msgs::CompressedImage &m, const std::string &file, const std::string &where) {
  return compressed_to_gray(m.format, m.data.data(), m.data.size(), file, where);
}

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

ImuData imu_from_message(const sensor_msgs::Imu &m, const std::string &file, const std::string &where) {
  ImuData d;
  d.t_imu_ns = static_cast<int64_t>(m.header.stamp.sec) * 1000000000LL + m.header.stamp.nsec;
  d.wm = Eigen::Vector3d(m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z);
  d.am = Eigen::Vector3d(m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z);
  check_imu_reading(d, file, where);
  return d;
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
