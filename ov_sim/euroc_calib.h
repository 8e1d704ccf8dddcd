#pragma once
// The EuRoC MAV sensors (VI-Sensor cam0 MT9M034, ADIS16448), typed from mav0/{cam0,imu0}/sensor.yaml of the
// EuRoC sequences. Built in so that `ovton simulate` works without any input file; config/sim/ carries the
// same values in EuRoC sensor.yaml format, and a test checks the two agree.
#include "ov_core/cam/camera_calib.h"
#include <string>

namespace ovton::sim {

ovton::core::CameraCalib euroc_cam0_calib();
/// The VI-Sensor's second camera (cam1, MT9M034), as mav0/cam1/sensor.yaml of V1_01_easy gives it: 11 cm to the
/// side of cam0, the stereo pair's extrinsics.
ovton::core::CameraCalib euroc_cam1_calib();
ovton::core::ImuCalib euroc_imu0_calib();

/// EuRoC-format sensor.yaml text (the layout of the original files, `%YAML:1.0` header included).
std::string euroc_camera_yaml(const ovton::core::CameraCalib &c, const std::string &comment);
std::string euroc_imu_yaml(const ovton::core::ImuCalib &c, const std::string &comment);

} // namespace ovton::sim
