// ROS 2 message definitions (the .msg files of sensor_msgs, std_msgs, builtin_interfaces, geometry_msgs) as rosbag2
// stores them in an MCAP schema: the type's own text, then each dependency after a line of 80 '=' and "MSG: pkg/Type".
// Written here from the ROS 2 interface definitions, independently of ovton's ov_core/io/ros2_schemas.cpp.
const SEP = "=".repeat(80);

const TIME = "int32 sec\nuint32 nanosec";
const HEADER = "builtin_interfaces/Time stamp\nstring frame_id";
const VECTOR3 = "float64 x\nfloat64 y\nfloat64 z";
const QUATERNION = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1";

function withDeps(own, deps) {
  return [own, ...deps.map(([name, text]) => `${SEP}\nMSG: ${name}\n${text}`)].join("\n") + "\n";
}

export const SCHEMAS = {
  "sensor_msgs/msg/Image": withDeps(
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data",
    [["std_msgs/Header", HEADER], ["builtin_interfaces/Time", TIME]],
  ),
  "sensor_msgs/msg/CompressedImage": withDeps("std_msgs/Header header\nstring format\nuint8[] data", [
    ["std_msgs/Header", HEADER],
    ["builtin_interfaces/Time", TIME],
  ]),
  "sensor_msgs/msg/Imu": withDeps(
    [
      "std_msgs/Header header",
      "geometry_msgs/Quaternion orientation",
      "float64[9] orientation_covariance",
      "geometry_msgs/Vector3 angular_velocity",
      "float64[9] angular_velocity_covariance",
      "geometry_msgs/Vector3 linear_acceleration",
      "float64[9] linear_acceleration_covariance",
    ].join("\n"),
    [
      ["std_msgs/Header", HEADER],
      ["builtin_interfaces/Time", TIME],
      ["geometry_msgs/Quaternion", QUATERNION],
      ["geometry_msgs/Vector3", VECTOR3],
    ],
  ),
};
