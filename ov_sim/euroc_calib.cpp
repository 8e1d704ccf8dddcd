#include "ov_sim/euroc_calib.h"
#include <cstdio>
#include <sstream>

namespace ovton::sim {

ovton::core::CameraCalib euroc_cam0_calib() {
  ovton::core::CameraCalib c;
  c.width = 752;
  c.height = 480;
  c.rate_hz = 20.0;
  c.intrinsics << 458.654, 457.296, 367.215, 248.375;
  c.distortion = ovton::core::DistortionModel::RadTan;
  c.dist_coeffs << -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05;
  c.T_BC << 0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975, //
      0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,           //
      -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,       //
      0.0, 0.0, 0.0, 1.0;
  return c;
}

ovton::core::CameraCalib euroc_cam1_calib() {
  ovton::core::CameraCalib c;
  c.width = 752;
  c.height = 480;
  c.rate_hz = 20.0;
  c.intrinsics << 457.587, 456.134, 379.999, 255.238;
  c.distortion = ovton::core::DistortionModel::RadTan;
  c.dist_coeffs << -0.28368365, 0.07451284, -0.00010473, -3.55590700e-05;
  c.T_BC << 0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556, //
      0.999598781151, 0.0130119051815, 0.0251588363115, 0.0453689425024,         //
      -0.0253898008918, 0.0179005838253, 0.999517347078, 0.00786212447038,       //
      0.0, 0.0, 0.0, 1.0;
  return c;
}

ovton::core::ImuCalib euroc_imu0_calib() {
  ovton::core::ImuCalib c;
  c.rate_hz = 200.0;
  c.gyro_noise_density = 1.6968e-04;
  c.gyro_random_walk = 1.9393e-05;
  c.accel_noise_density = 2.0000e-3;
  c.accel_random_walk = 3.0000e-3;
  c.T_BI.setIdentity();
  return c;
}

namespace {
std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.15g", v); // shortest text that reads back to the same double for these
  return buf;
}

void write_T(std::ostringstream &os, const Eigen::Matrix4d &T) {
  os << "T_BS:\n  cols: 4\n  rows: 4\n  data: [";
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      os << num(T(r, c)) << (r == 3 && c == 3 ? "]\n" : (c == 3 ? ",\n         " : ", "));
}
} // namespace

std::string euroc_camera_yaml(const ovton::core::CameraCalib &c, const std::string &comment) {
  std::ostringstream os;
  os << "%YAML:1.0\n# General sensor definitions.\nsensor_type: camera\ncomment: " << comment
     << "\n\n# Sensor extrinsics wrt. the body-frame.\n";
  write_T(os, c.T_BC);
  os << "\n# Camera specific definitions.\nrate_hz: " << num(c.rate_hz) << "\nresolution: [" << c.width << ", "
     << c.height << "]\ncamera_model: pinhole\nintrinsics: [" << num(c.intrinsics(0)) << ", " << num(c.intrinsics(1))
     << ", " << num(c.intrinsics(2)) << ", " << num(c.intrinsics(3)) << "] #fu, fv, cu, cv\ndistortion_model: "
     << (c.distortion == ovton::core::DistortionModel::RadTan ? "radial-tangential" : "equidistant")
     << "\ndistortion_coefficients: [" << num(c.dist_coeffs(0)) << ", " << num(c.dist_coeffs(1)) << ", "
     << num(c.dist_coeffs(2)) << ", " << num(c.dist_coeffs(3)) << "]\n";
  return os.str();
}

std::string euroc_imu_yaml(const ovton::core::ImuCalib &c, const std::string &comment) {
  std::ostringstream os;
  os << "%YAML:1.0\n#Default imu sensor yaml file\nsensor_type: imu\ncomment: " << comment
     << "\n\n# Sensor extrinsics wrt. the body-frame.\n";
  write_T(os, c.T_BI);
  os << "rate_hz: " << num(c.rate_hz) << "\n\n# inertial sensor noise model parameters (static)\n"
     << "gyroscope_noise_density: " << num(c.gyro_noise_density)
     << "     # [ rad / s / sqrt(Hz) ]   ( gyro \"white noise\" )\n"
     << "gyroscope_random_walk: " << num(c.gyro_random_walk)
     << "       # [ rad / s^2 / sqrt(Hz) ] ( gyro bias diffusion )\n"
     << "accelerometer_noise_density: " << num(c.accel_noise_density)
     << "  # [ m / s^2 / sqrt(Hz) ]   ( accel \"white noise\" )\n"
     << "accelerometer_random_walk: " << num(c.accel_random_walk)
     << "    # [ m / s^3 / sqrt(Hz) ].  ( accel bias diffusion )\n";
  return os.str();
}

} // namespace ovton::sim
