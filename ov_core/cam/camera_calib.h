#pragma once
#include <Eigen/Core>
#include <string>

namespace ovton::core {

enum class DistortionModel { RadTan, Equidistant };

/// Intrinsics and extrinsics of one camera, as EuRoC cam0/sensor.yaml or a Kalibr camchain gives them.
struct CameraCalib {
  int width = 0;
  int height = 0;
  double rate_hz = 0.0;
  Eigen::Vector4d intrinsics = Eigen::Vector4d::Zero(); ///< fu, fv, cu, cv [px]
  DistortionModel distortion = DistortionModel::RadTan;
  Eigen::Vector4d dist_coeffs = Eigen::Vector4d::Zero(); ///< radtan: k1 k2 p1 p2; equidistant: k1..k4
  Eigen::Matrix4d T_BC = Eigen::Matrix4d::Identity();    ///< camera -> body (EuRoC T_BS, Kalibr T_imu_cam)
};

/// Continuous-time IMU noise model (EuRoC imu0/sensor.yaml units).
struct ImuCalib {
  double rate_hz = 200.0;
  double gyro_noise_density = 0.0;  ///< rad/s/sqrt(Hz)
  double gyro_random_walk = 0.0;    ///< rad/s^2/sqrt(Hz)
  double accel_noise_density = 0.0; ///< m/s^2/sqrt(Hz)
  double accel_random_walk = 0.0;   ///< m/s^3/sqrt(Hz)
  Eigen::Matrix4d T_BI = Eigen::Matrix4d::Identity();
};

std::string to_string(DistortionModel m);

/// R_IC: camera -> IMU rotation (both calibrations' body-frame extrinsics).
inline Eigen::Matrix3d camera_to_imu_rotation(const CameraCalib &cam, const ImuCalib &imu) {
  return imu.T_BI.block<3, 3>(0, 0).transpose() * cam.T_BC.block<3, 3>(0, 0);
}

} // namespace ovton::core
