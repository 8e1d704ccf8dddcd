#pragma once
// sensor_msgs/Image, CompressedImage and Imu to and from ovton's types, with the checks that name the bag and message.
// Included only by the rosbag reader and writer (it pulls in the ROS message headers).
#include "ov_core/types/sensor_data.h"

#include <opencv2/core.hpp>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>

#include <string>

namespace ovton::core {

/// Throws DataError(file, where + ...) unless the message is an image ovton can read (encoding mono8, mono16, bgr8,
/// rgb8, bgra8 or rgba8; data size consistent with step and height) of the calibration's width x height.
void check_image_message(const sensor_msgs::Image &m, int width, int height, const std::string &file,
                         const std::string &where);
/// 8-bit grayscale pixels of a checked message (colour by OpenCV's luma weights, mono16 by its upper 8 bits).
cv::Mat image_to_gray(const sensor_msgs::Image &m, const std::string &file, const std::string &where);
/// The same for sensor_msgs/CompressedImage (JPEG or PNG; the size is read from the file's header, image_message.h).
void check_image_message(const sensor_msgs::CompressedImage &m, int width, int height, const std::string &file,
                         const std::string &where);
cv::Mat image_to_gray(const sensor_msgs::CompressedImage &m, const std::string &file, const std::string &where);
/// gray (CV_8UC1) as a mono8 message stamped t_cam_ns.
sensor_msgs::Image gray_to_message(const cv::Mat &gray, int64_t t_cam_ns, const std::string &frame_id);

/// IMU reading of a message; throws DataError for non-finite values or a negative stamp.
ImuData imu_from_message(const sensor_msgs::Imu &m, const std::string &file, const std::string &where);
sensor_msgs::Imu imu_to_message(const ImuData &d, const std::string &frame_id);

/// A stamp in ROS time; throws UsageError for stamps ROS 1 cannot hold (negative, or past 2106).
ros::Time to_ros_time(int64_t t_ns);

} // namespace ovton::core
