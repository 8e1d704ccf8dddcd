#pragma once
// Kalibr calibration files (camchain-imucam.yaml, imu.yaml) written from ovton's calibration, so that an exported bag
// carries its calibration the way a Kalibr user's bag does. Numbers are written with 17 significant digits (they read
// back to the same doubles).
#include "ov_core/cam/camera_calib.h"

#include <string>
#include <vector>

namespace ovton::core {

/// cam0 with T_cam_imu = T_BC⁻¹ (Kalibr's convention), timeshift_cam_imu = td_prior_s, and its rostopic.
void write_kalibr_camchain(const std::string &file, const CameraCalib &cam, double td_prior_s,
                           const std::string &rostopic);
/// A rig: camN for cams[N], each with its own T_cam_imu and rostopics[N] (the rig's one time shift).
void write_kalibr_rig(const std::string &file, const std::vector<CameraCalib> &cams, double td_prior_s,
                      const std::vector<std::string> &rostopics);
void write_kalibr_imu(const std::string &file, const ImuCalib &imu, const std::string &rostopic);

} // namespace ovton::core
