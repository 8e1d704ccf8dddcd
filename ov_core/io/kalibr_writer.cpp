#include "ov_core/io/kalibr_writer.h"
#include "ov_core/types/errors.h"

#include <Eigen/LU>

#include <cstdio>
#include <fstream>
#include <sstream>

namespace ovton::core {

namespace {

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

template <typename V> std::string list(const V &v) {
  std::string s = "[";
  for (int i = 0; i < static_cast<int>(v.size()); ++i)
    s += (i ? ", " : "") + num(v(i));
  return s + "]";
}

void write_text(const std::string &file, const std::string &text) {
  std::ofstream out(file);
  if (!(out << text) || !out.flush())
    throw DataError(file, "cannot write");
}

} // namespace

void write_kalibr_camchain(const std::string &file, const CameraCalib &cam, double td_prior_s,
                           const std::string &rostopic) {
  write_kalibr_rig(file, {cam}, td_prior_s, {rostopic});
}

void write_kalibr_rig(const std::string &file, const std::vector<CameraCalib> &cams, double td_prior_s,
                      const std::vector<std::string> &rostopics) {
  std::ostringstream o;
  o << "# Kalibr camchain written by ovton export: T_cam_imu maps IMU-frame points into the camera frame.\n";
  for (size_t k = 0; k < cams.size(); ++k) {
    const CameraCalib &cam = cams[k];
    const Eigen::Matrix4d T_CI = cam.T_BC.inverse();
    o << "cam" << k << ":\n  T_cam_imu:\n";
    // The rows indented under their key: valid YAML either way, but OpenCV's FileStorage (which OpenVINS reads its
    // camchain with) refuses a block sequence at its key's indentation ("Incorrect indentation").
    for (int r = 0; r < 4; ++r)
      o << "    - " << list(T_CI.row(r).transpose().eval()) << "\n";
    o << "  camera_model: pinhole\n"
      << "  distortion_model: " << (cam.distortion == DistortionModel::RadTan ? "radtan" : "equidistant") << "\n"
      << "  distortion_coeffs: " << list(cam.dist_coeffs) << "\n"
      << "  intrinsics: " << list(cam.intrinsics) << "\n"
      << "  resolution: [" << cam.width << ", " << cam.height << "]\n"
      << "  rate_hz: " << num(cam.rate_hz) << "\n"
      << "  timeshift_cam_imu: " << num(td_prior_s) << "\n"
      << "  rostopic: " << rostopics.at(k) << "\n";
  }
  write_text(file, o.str());
}

void write_kalibr_imu(const std::string &file, const ImuCalib &imu, const std::string &rostopic) {
  std::ostringstream o;
  o << "# Kalibr IMU noise model written by ovton export (continuous-time densities).\n"
    << "imu0:\n"
    << "  accelerometer_noise_density: " << num(imu.accel_noise_density) << "\n"
    << "  accelerometer_random_walk: " << num(imu.accel_random_walk) << "\n"
    << "  gyroscope_noise_density: " << num(imu.gyro_noise_density) << "\n"
    << "  gyroscope_random_walk: " << num(imu.gyro_random_walk) << "\n"
    << "  model: calibrated\n"
    << "  rostopic: " << rostopic << "\n"
    << "  update_rate: " << num(imu.rate_hz) << "\n";
  write_text(file, o.str());
}

} // namespace ovton::core
