#pragma once
// The ROS 2 messages ovton reads and writes, in CDR (cdr.h): sensor_msgs Image, CompressedImage, Imu and CameraInfo,
// and tf2_msgs TFMessage (a camera's extrinsics from /tf_static). Readers name the recording (file) and the message
// (where) in every error.
#include "ov_core/cam/camera_calib.h"
#include "ov_core/io/cdr.h"
#include "ov_core/io/image_message.h"
#include "ov_core/types/sensor_data.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>
#include <string>
#include <vector>

namespace ovton::core {

/// The message types ovton reads, by the names ROS 2 gives them ("sensor_msgs/msg/Image"; "sensor_msgs/Image", the
/// name some writers use, is read the same).
enum class Ros2Type { Image, CompressedImage, Imu, CameraInfo, TfMessage, Other };
Ros2Type ros2_type(const std::string &name);

struct Ros2Header {
  int64_t stamp_ns = 0; ///< the sensor's stamp (builtin_interfaces/Time), not the recorder's receive time
  std::string frame_id;
};

struct Ros2Image {
  Ros2Header header;
  RawImageView pixels; ///< pixels.data null when only the message's first bytes were given
};

struct Ros2CompressedImage {
  Ros2Header header;
  std::string format;
  CdrReader::Bytes data;
};

struct Ros2CameraInfo {
  Ros2Header header;
  uint32_t width = 0, height = 0;
  std::string distortion_model;
  std::vector<double> d;
  std::array<double, 9> k{};
};

/// One transform of a TFMessage: T_parent_child maps child-frame points into the parent frame.
struct Ros2Transform {
  int64_t stamp_ns = 0;
  std::string parent, child;
  Eigen::Matrix4d T_parent_child = Eigen::Matrix4d::Identity();
};

/// Decoders. `size` bytes of the message are at `data`; an image may be given as its first bytes only, `full_size`
/// being the whole message's (its header, size and encoding are then checked without the pixels). Wire::Ros1 reads the
/// same messages as a ROS 1 bag stores them (the fields are the same; the header has a seq).
Ros2Image decode_ros2_image(const uint8_t *data, size_t size, const std::string &file, const std::string &where,
                            size_t full_size = 0, Wire wire = Wire::Cdr);
Ros2CompressedImage decode_ros2_compressed_image(const uint8_t *data, size_t size, const std::string &file,
                                                 const std::string &where, size_t full_size = 0, Wire wire = Wire::Cdr);
/// Throws DataError for non-finite rates. `frame_id`, when given, receives the header's frame.
ImuData decode_ros2_imu(const uint8_t *data, size_t size, const std::string &file, const std::string &where,
                        std::string *frame_id = nullptr, Wire wire = Wire::Cdr);
Ros2CameraInfo decode_ros2_camera_info(const uint8_t *data, size_t size, const std::string &file,
                                       const std::string &where);
std::vector<Ros2Transform> decode_ros2_tf(const uint8_t *data, size_t size, const std::string &file,
                                          const std::string &where);

/// A camera calibration from CameraInfo (distortion plumb_bob with k3 = 0 as radtan, equidistant) and the extrinsics
/// T_BC given; throws DataError for other models or an invalid K.
CameraCalib camera_from_info(const Ros2CameraInfo &info, const Eigen::Matrix4d &T_BC, const std::string &file,
                             const std::string &where);

/// Encoders (CDR little-endian). A builtin_interfaces/Time; throws UsageError beyond its int32 seconds.
void write_ros2_time(CdrWriter &w, int64_t t_ns);
void write_ros2_header(CdrWriter &w, int64_t stamp_ns, const std::string &frame_id);
std::vector<uint8_t> encode_ros2_image(const cv::Mat &gray, int64_t stamp_ns, const std::string &frame_id);
std::vector<uint8_t> encode_ros2_compressed_image(const std::vector<uint8_t> &bytes, const std::string &format,
                                                  int64_t stamp_ns, const std::string &frame_id);
std::vector<uint8_t> encode_ros2_imu(const ImuData &d, const std::string &frame_id);
std::vector<uint8_t> encode_ros2_camera_info(const CameraCalib &cam, int64_t stamp_ns, const std::string &frame_id);
std::vector<uint8_t> encode_ros2_tf(const std::vector<Ros2Transform> &tf);
/// geometry_msgs Transform / Pose bodies (translation or position, then the rotation as x, y, z, w).
void write_ros2_pose(CdrWriter &w, const Eigen::Vector3d &p, const Eigen::Quaterniond &q);

} // namespace ovton::core
