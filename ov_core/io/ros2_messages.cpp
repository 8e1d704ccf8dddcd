#include "ov_core/io/ros2_messages.h"
#include "ov_core/io/recording_topics.h"
#include "ov_core/types/errors.h"

#include <Eigen/Geometry>

#include <cmath>
#include <limits>

namespace ovton::core {

namespace {

Ros2Header read_header(CdrReader &r) {
  Ros2Header h;
  if (r.wire() == Wire::Ros1)
    r.u32("header.seq");
  // ROS 1's seconds are unsigned, ROS 2's signed.
  const int64_t sec =
      r.wire() == Wire::Ros1 ? static_cast<int64_t>(r.u32("header.stamp.secs")) : r.i32("header.stamp.sec");
  const uint32_t nsec = r.u32("header.stamp.nanosec");
  if (nsec >= 1000000000u)
    r.fail("header.stamp.nanosec " + std::to_string(nsec) + " is not below 10^9");
  h.stamp_ns = sec * 1000000000LL + nsec;
  h.frame_id = r.string("header.frame_id");
  return h;
}

Eigen::Vector3d read_vector3(CdrReader &r, const char *field) {
  Eigen::Vector3d v;
  r.f64_array(v.data(), 3, field);
  return v;
}

} // namespace

Ros2Type ros2_type(const std::string &name) {
  const auto at = name.find("/msg/");
  const std::string n = at == std::string::npos ? name : name.substr(0, at) + "/" + name.substr(at + 5);
  if (n == "sensor_msgs/Image")
    return Ros2Type::Image;
  if (n == "sensor_msgs/CompressedImage")
    return Ros2Type::CompressedImage;
  if (n == "sensor_msgs/Imu")
    return Ros2Type::Imu;
  if (n == "sensor_msgs/CameraInfo")
    return Ros2Type::CameraInfo;
  if (n == "tf2_msgs/TFMessage")
    return Ros2Type::TfMessage;
  return Ros2Type::Other;
}

Ros2Image decode_ros2_image(const uint8_t *data, size_t size, const std::string &file, const std::string &where,
                            size_t full_size, Wire wire) {
  CdrReader r(data, size, file, where, full_size, wire);
  Ros2Image m;
  m.header = read_header(r);
  m.pixels.height = r.u32("height");
  m.pixels.width = r.u32("width");
  m.pixels.encoding = r.string("encoding");
  m.pixels.big_endian = r.u8("is_bigendian") != 0;
  m.pixels.step = r.u32("step");
  const CdrReader::Bytes b = r.seq_bytes("data");
  m.pixels.data = b.data;
  m.pixels.size = b.size;
  return m;
}

Ros2CompressedImage decode_ros2_compressed_image(const uint8_t *data, size_t size, const std::string &file,
                                                 const std::string &where, size_t full_size, Wire wire) {
  CdrReader r(data, size, file, where, full_size, wire);
  Ros2CompressedImage m;
  m.header = read_header(r);
  m.format = r.string("format");
  m.data = r.seq_bytes("data");
  return m;
}

ImuData decode_ros2_imu(const uint8_t *data, size_t size, const std::string &file, const std::string &where,
                        std::string *frame_id, Wire wire) {
  CdrReader r(data, size, file, where, 0, wire);
  ImuData d;
  Ros2Header h = read_header(r);
  d.t_imu_ns = h.stamp_ns;
  if (frame_id)
    *frame_id = std::move(h.frame_id);
  double skip[9];
  r.f64_array(skip, 4, "orientation");
  r.f64_array(skip, 9, "orientation_covariance");
  d.wm = read_vector3(r, "angular_velocity");
  r.f64_array(skip, 9, "angular_velocity_covariance");
  d.am = read_vector3(r, "linear_acceleration");
  r.f64_array(skip, 9, "linear_acceleration_covariance");
  check_imu_reading(d, file, where);
  return d;
}

Ros2CameraInfo decode_ros2_camera_info(const uint8_t *data, size_t size, const std::string &file,
                                       const std::string &where) {
  CdrReader r(data, size, file, where);
  Ros2CameraInfo m;
  m.header = read_header(r);
  m.height = r.u32("height");
  m.width = r.u32("width");
  m.distortion_model = r.string("distortion_model");
  m.d.resize(r.seq_length(8, "d"));
  r.f64_array(m.d.data(), m.d.size(), "d");
  r.f64_array(m.k.data(), 9, "k");
  return m; // r, p, binning and roi are not needed
}

std::vector<Ros2Transform> decode_ros2_tf(const uint8_t *data, size_t size, const std::string &file,
                                          const std::string &where) {
  CdrReader r(data, size, file, where);
  std::vector<Ros2Transform> out(r.seq_length(16, "transforms"));
  for (Ros2Transform &t : out) {
    const Ros2Header h = read_header(r);
    t.stamp_ns = h.stamp_ns;
    t.parent = h.frame_id;
    t.child = r.string("child_frame_id");
    const Eigen::Vector3d p = read_vector3(r, "transform.translation");
    double q[4];
    r.f64_array(q, 4, "transform.rotation");
    const Eigen::Quaterniond rot(q[3], q[0], q[1], q[2]);
    if (!p.allFinite() || !(std::abs(rot.norm() - 1.0) < 1e-3))
      r.fail("transform " + t.parent + " -> " + t.child + " is not finite or its rotation is not a unit quaternion");
    t.T_parent_child.topLeftCorner<3, 3>() = rot.normalized().toRotationMatrix();
    t.T_parent_child.topRightCorner<3, 1>() = p;
  }
  return out;
}

CameraCalib camera_from_info(const Ros2CameraInfo &info, const Eigen::Matrix4d &T_BC, const std::string &file,
                             const std::string &where) {
  CameraCalib c;
  c.width = static_cast<int>(info.width);
  c.height = static_cast<int>(info.height);
  c.intrinsics << info.k[0], info.k[4], info.k[2], info.k[5];
  if (!(info.k[0] > 0 && info.k[4] > 0) || !c.intrinsics.allFinite() || c.width <= 0 || c.height <= 0)
    throw DataError(file, where + ": CameraInfo has no valid camera matrix k (fx, fy > 0) or size");
  const std::string &model = info.distortion_model;
  const auto &d = info.d;
  const auto zero_from = [&](size_t i) {
    for (; i < d.size(); ++i)
      if (d[i] != 0.0)
        return false;
    return true;
  };
  if (model == "equidistant" || model == "fisheye") {
    if (d.size() < 4 || !zero_from(4))
      throw DataError(file, where + ": CameraInfo model " + model + " needs 4 coefficients k1..k4");
    c.distortion = DistortionModel::Equidistant;
    c.dist_coeffs << d[0], d[1], d[2], d[3];
  } else if (model == "plumb_bob" || model == "rational_polynomial" || (model.empty() && d.empty())) {
    // ovton's radial-tangential model has k1 k2 p1 p2: a k3 (or the rational model's k4..k6) must be zero.
    if (!zero_from(4))
      throw DataError(file, where + ": CameraInfo " + model +
                                " distortion with k3 or higher terms is not supported "
                                "(ovton's radtan model has k1 k2 p1 p2); give a Kalibr calibration with --calib");
    c.distortion = DistortionModel::RadTan;
    for (size_t i = 0; i < 4 && i < d.size(); ++i)
      c.dist_coeffs[static_cast<int>(i)] = d[i];
  } else {
    throw DataError(file, where + ": CameraInfo distortion model '" + model +
                              "' is not supported (plumb_bob, rational_polynomial with k3..k6 = 0, equidistant)");
  }
  if (!c.dist_coeffs.allFinite())
    throw DataError(file, where + ": CameraInfo distortion coefficients are not finite");
  c.T_BC = T_BC;
  return c;
}

void write_ros2_time(CdrWriter &w, int64_t t_ns) {
  const int64_t sec = t_ns >= 0 ? t_ns / 1000000000LL : -((-t_ns + 999999999LL) / 1000000000LL);
  if (sec < std::numeric_limits<int32_t>::min() || sec > std::numeric_limits<int32_t>::max())
    throw UsageError("stamp " + std::to_string(t_ns) + " ns does not fit a ROS 2 time (int32 seconds)");
  w.i32(static_cast<int32_t>(sec));
  w.u32(static_cast<uint32_t>(t_ns - sec * 1000000000LL));
}

void write_ros2_header(CdrWriter &w, int64_t stamp_ns, const std::string &frame_id) {
  write_ros2_time(w, stamp_ns);
  w.string(frame_id);
}

std::vector<uint8_t> encode_ros2_image(const cv::Mat &gray, int64_t stamp_ns, const std::string &frame_id) {
  if (gray.type() != CV_8UC1)
    throw UsageError("encode_ros2_image: expected an 8-bit single-channel image");
  CdrWriter w;
  write_ros2_header(w, stamp_ns, frame_id);
  w.u32(static_cast<uint32_t>(gray.rows));
  w.u32(static_cast<uint32_t>(gray.cols));
  w.string("mono8");
  w.u8(0);
  w.u32(static_cast<uint32_t>(gray.cols));
  const cv::Mat dense = gray.isContinuous() ? gray : gray.clone();
  w.seq_bytes(dense.data, dense.total());
  return w.take();
}

std::vector<uint8_t> encode_ros2_compressed_image(const std::vector<uint8_t> &bytes, const std::string &format,
                                                  int64_t stamp_ns, const std::string &frame_id) {
  CdrWriter w;
  write_ros2_header(w, stamp_ns, frame_id);
  w.string(format);
  w.seq_bytes(bytes.data(), bytes.size());
  return w.take();
}

std::vector<uint8_t> encode_ros2_imu(const ImuData &d, const std::string &frame_id) {
  CdrWriter w;
  write_ros2_header(w, d.t_imu_ns, frame_id);
  const double no_orientation[4] = {0, 0, 0, 1};
  w.f64_array(no_orientation, 4);
  // No orientation estimate: REP 145 marks that with -1 in the first covariance entry.
  double cov[9] = {-1, 0, 0, 0, 0, 0, 0, 0, 0};
  w.f64_array(cov, 9);
  cov[0] = 0;
  w.f64_array(d.wm.data(), 3);
  w.f64_array(cov, 9);
  w.f64_array(d.am.data(), 3);
  w.f64_array(cov, 9);
  return w.take();
}

std::vector<uint8_t> encode_ros2_camera_info(const CameraCalib &cam, int64_t stamp_ns, const std::string &frame_id) {
  CdrWriter w;
  write_ros2_header(w, stamp_ns, frame_id);
  w.u32(static_cast<uint32_t>(cam.height));
  w.u32(static_cast<uint32_t>(cam.width));
  const bool eq = cam.distortion == DistortionModel::Equidistant;
  w.string(eq ? "equidistant" : "plumb_bob");
  const auto &k = cam.dist_coeffs;
  const std::vector<double> d =
      eq ? std::vector<double>{k[0], k[1], k[2], k[3]} : std::vector<double>{k[0], k[1], k[2], k[3], 0.0};
  w.seq_length(d.size());
  w.f64_array(d.data(), d.size());
  const auto &in = cam.intrinsics;
  const double K[9] = {in[0], 0, in[2], 0, in[1], in[3], 0, 0, 1};
  const double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const double P[12] = {in[0], 0, in[2], 0, 0, in[1], in[3], 0, 0, 0, 1, 0};
  w.f64_array(K, 9);
  w.f64_array(R, 9);
  w.f64_array(P, 12);
  for (int i = 0; i < 6; ++i) // binning_x, binning_y, roi x_offset, y_offset, height, width
    w.u32(0);
  w.boolean(false); // roi.do_rectify
  return w.take();
}

void write_ros2_pose(CdrWriter &w, const Eigen::Vector3d &p, const Eigen::Quaterniond &q) {
  w.f64_array(p.data(), 3);
  const double xyzw[4] = {q.x(), q.y(), q.z(), q.w()};
  w.f64_array(xyzw, 4);
}

std::vector<uint8_t> encode_ros2_tf(const std::vector<Ros2Transform> &tf) {
  CdrWriter w;
  w.seq_length(tf.size());
  for (const Ros2Transform &t : tf) {
    write_ros2_header(w, t.stamp_ns, t.parent);
    w.string(t.child);
    const Eigen::Matrix3d R = t.T_parent_child.topLeftCorner<3, 3>();
    write_ros2_pose(w, t.T_parent_child.topRightCorner<3, 1>(), Eigen::Quaterniond(R));
  }
  return w.take();
}

} // namespace ovton::core
