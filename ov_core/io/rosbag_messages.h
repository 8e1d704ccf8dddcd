#pragma once
// ovton's types as ROS 1 sensor_msgs/Image and sensor_msgs/Imu, for the bag writer (the reader decodes a bag's message
// bytes itself: ros2_messages.h, Wire::Ros1). Included only by the rosbag writer (it pulls in the ROS message headers).
#include "ov_core/types/sensor_data.h"

#include <opencv2/core.hpp>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>

#include <string>

namespace ovton::core {

/// gray (CV_8UC1) as a mono8 message stamped t_cam_ns.
sensor_msgs::Image gray_to_message(const cv::Mat &gray, int64_t t_cam_ns, const std::string &frame_id);
sensor_msgs::Imu imu_to_message(const ImuData &d, const std::string &frame_id);

/// A stamp in ROS time; throws UsageError for stamps ROS 1 cannot hold (negative, or past 2106).
ros::Time to_ros_time(int64_t t_ns);

} // namespace ovton::core
