#include "ov_core/io/rosbag_messages.h"
#include "ov_core/types/errors.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstring>
#include <limits>

namespace ovton::core {

namespace {

struct Encoding {
  const char *name;
  int channels;
  int bytes_per_channel;
  int to_gray; ///< cv::cvtColor code, -1 for none
};

constexpr Encoding kEncodings[] = {
    {"mono8", 1, 1, -1},
    {"8UC1", 1, 1, -1},
    {"mono16", 1, 2, -1},
    {"16UC1", 1, 2, -1},
    {"bgr8", 3, 1, cv::COLOR_BGR2GRAY},
    {"rgb8", 3, 1, cv::COLOR_RGB2GRAY},
    {"bgra8", 4, 1, cv::COLOR_BGRA2GRAY},
    {"rgba8", 4, 1, cv::COLOR_RGBA2GRAY},
};

const Encoding *find_encoding(const std::string &name) {
  for (const auto &e : kEncodings)
    if (name == e.name)
      return &e;
  return nullptr;
}

} // namespace

void check_image_message(const sensor_msgs::Image &m, int width, int height, const std::string &file,
                         const std::string &where) {
  const Encoding *enc = find_encoding(m.encoding);
  if (!enc)
    throw DataError(file, where + ": unsupported image encoding '" + m.encoding +
                              "' (supported: mono8, mono16, bgr8, rgb8, bgra8, rgba8)");
  if (static_cast<int>(m.width) != width || static_cast<int>(m.height) != height)
    throw DataError(file, where + ": image is " + std::to_string(m.width) + "x" + std::to_string(m.height) +
                              " px, the camera calibration says " + std::to_string(width) + "x" +
                              std::to_string(height));
  const uint64_t row = static_cast<uint64_t>(m.width) * enc->channels * enc->bytes_per_channel;
  if (m.step < row || static_cast<uint64_t>(m.step) * m.height != m.data.size())
    throw DataError(file, where + ": " + std::to_string(m.data.size()) + " bytes of pixels do not fit " +
                              std::to_string(m.width) + "x" + std::to_string(m.height) + " " + m.encoding +
                              " with a row step of " + std::to_string(m.step));
}

cv::Mat image_to_gray(const sensor_msgs::Image &m, const std::string &file, const std::string &where) {
  check_image_message(m, static_cast<int>(m.width), static_cast<int>(m.height), file, where);
  const Encoding *enc = find_encoding(m.encoding);
  const int type = CV_MAKETYPE(enc->bytes_per_channel == 1 ? CV_8U : CV_16U, enc->channels);
  // A view of the message's bytes (rows may be padded: step), copied out by the conversions below.
  const cv::Mat view(static_cast<int>(m.height), static_cast<int>(m.width), type, const_cast<uint8_t *>(m.data.data()),
                     m.step);
  cv::Mat gray;
  if (enc->bytes_per_channel == 2) {
    cv::Mat swapped;
    const bool host_big_endian = cv::Mat(1, 1, CV_16U, cv::Scalar(1)).data[0] == 0;
    if (static_cast<bool>(m.is_bigendian) != host_big_endian) {
      swapped = view.clone();
      for (int r = 0; r < swapped.rows; ++r) {
        auto *p = swapped.ptr<uint16_t>(r);
        for (int c = 0; c < swapped.cols; ++c)
          p[c] = static_cast<uint16_t>((p[c] >> 8) | (p[c] << 8));
      }
    }
    (swapped.empty() ? view : swapped).convertTo(gray, CV_8U, 1.0 / 256.0);
  } else if (enc->to_gray >= 0) {
    cv::cvtColor(view, gray, enc->to_gray);
  } else {
    gray = view.clone();
  }
  return gray;
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
  if (!d.wm.allFinite() || !d.am.allFinite())
    throw DataError(file, where + ": non-finite angular velocity or linear acceleration");
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
