#include "ov_core/io/ros2_schemas.h"
#include "ov_core/types/errors.h"

#include <map>
#include <set>
#include <vector>

namespace ovton::core {

namespace {

/// Each type's own fields (the .msg text without comments), keyed by the name its users write ("pkg/Type").
const std::map<std::string, std::string> &definitions() {
  static const std::map<std::string, std::string> defs = {
      {"builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"},
      {"std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id\n"},
      {"std_msgs/Float64", "float64 data\n"},
      {"geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"},
      {"geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n"},
      {"geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"},
      {"geometry_msgs/Pose", "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n"},
      {"geometry_msgs/PoseStamped", "std_msgs/Header header\ngeometry_msgs/Pose pose\n"},
      {"geometry_msgs/Transform", "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n"},
      {"geometry_msgs/TransformStamped",
       "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n"},
      {"tf2_msgs/TFMessage", "geometry_msgs/TransformStamped[] transforms\n"},
      {"nav_msgs/Path", "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses\n"},
      {"sensor_msgs/Image", "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\n"
                            "uint32 step\nuint8[] data\n"},
      {"sensor_msgs/CompressedImage", "std_msgs/Header header\nstring format\nuint8[] data\n"},
      {"sensor_msgs/Imu", "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\n"
                          "float64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\n"
                          "float64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\n"
                          "float64[9] linear_acceleration_covariance\n"},
      {"sensor_msgs/RegionOfInterest",
       "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n"},
      {"sensor_msgs/CameraInfo", "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n"
                                 "float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\n"
                                 "uint32 binning_y\nsensor_msgs/RegionOfInterest roi\n"},
      {"foxglove_msgs/Point2", "float64 x\nfloat64 y\n"},
      {"foxglove_msgs/Color", "float64 r\nfloat64 g\nfloat64 b\nfloat64 a\n"},
      {"foxglove_msgs/CircleAnnotation", "builtin_interfaces/Time timestamp\nfoxglove_msgs/Point2 position\n"
                                         "float64 diameter\nfloat64 thickness\nfoxglove_msgs/Color fill_color\n"
                                         "foxglove_msgs/Color outline_color\n"},
      {"foxglove_msgs/PointsAnnotation",
       "builtin_interfaces/Time timestamp\nuint8 UNKNOWN=0\nuint8 POINTS=1\nuint8 LINE_LOOP=2\nuint8 LINE_STRIP=3\n"
       "uint8 LINE_LIST=4\nuint8 type\nfoxglove_msgs/Point2[] points\nfoxglove_msgs/Color outline_color\n"
       "foxglove_msgs/Color[] outline_colors\nfoxglove_msgs/Color fill_color\nfloat64 thickness\n"},
      {"foxglove_msgs/TextAnnotation", "builtin_interfaces/Time timestamp\nfoxglove_msgs/Point2 position\n"
                                       "string text\nfloat64 font_size\nfoxglove_msgs/Color text_color\n"
                                       "foxglove_msgs/Color background_color\n"},
      {"foxglove_msgs/ImageAnnotations", "foxglove_msgs/CircleAnnotation[] circles\n"
                                         "foxglove_msgs/PointsAnnotation[] points\n"
                                         "foxglove_msgs/TextAnnotation[] texts\n"},
  };
  return defs;
}

/// "pkg/msg/Type" -> "pkg/Type".
std::string short_name(const std::string &type) {
  const auto at = type.find("/msg/");
  return at == std::string::npos ? type : type.substr(0, at) + "/" + type.substr(at + 5);
}

/// The complex types a definition's fields use, in the order they appear.
std::vector<std::string> used_types(const std::string &def) {
  std::vector<std::string> out;
  size_t line = 0;
  while (line < def.size()) {
    const size_t end = def.find('\n', line);
    const std::string l = def.substr(line, end - line);
    const std::string type = l.substr(0, l.find(' '));
    const std::string base = type.substr(0, type.find('['));
    if (base.find('/') != std::string::npos)
      out.push_back(base);
    line = end + 1;
  }
  return out;
}

void append_dependencies(const std::string &type, std::set<std::string> &seen, std::string &out) {
  for (const std::string &dep : used_types(definitions().at(type))) {
    if (!seen.insert(dep).second)
      continue;
    out += std::string(80, '=') + "\nMSG: " + dep + "\n" + definitions().at(dep);
    append_dependencies(dep, seen, out);
  }
}

} // namespace

std::string ros2_schema(const std::string &type) {
  const std::string name = short_name(type);
  const auto it = definitions().find(name);
  if (it == definitions().end())
    throw UsageError("no ROS 2 message definition for " + type + " in ovton");
  std::string out = it->second;
  std::set<std::string> seen{name};
  append_dependencies(name, seen, out);
  return out;
}

} // namespace ovton::core
