#pragma once
// The ROS 2 message definitions ovton writes into MCAP files (schema encoding "ros2msg": the type's .msg text, then
// every type it uses, each after a line of 80 '=' and "MSG: pkg/Type", as rosbag2 writes them), so that ros2 bag play,
// Foxglove and any MCAP reader can decode the messages without the packages installed.
#include <string>

namespace ovton::core {

/// The full ros2msg schema of `type` ("sensor_msgs/msg/Image", "foxglove_msgs/msg/ImageAnnotations", ...): its own
/// definition followed by those of its dependencies. Throws UsageError for a type ovton does not write.
std::string ros2_schema(const std::string &type);

} // namespace ovton::core
