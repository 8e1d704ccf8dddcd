// `ovton calibrate`'s estimation (ov_msckf_ton/calib): on a rendered folder with a planted camera-IMU rotation, focal
// length, offset and readout, whose sensor.yaml files are then removed, the fit recovers each within a fixed
// tolerance and within 3 of its own σ; on the real phone recording (../shared) it finishes with finite values.
#include "ov_core/io/dataset.h"
#include "ov_core/math/so3.h"
#include "ov_msckf_ton/calib/camera_imu_calib.h"
#include "ov_sim/simulator.h"
#include "test_util.h"

#include <cmath>
#include <filesystem>
#include <gtest/gtest.h>
#include <iostream>

namespace {

constexpr double kDeg = M_PI / 180.0;

/// A phone-sized pinhole without distortion (640x480, 30 Hz), mounted as EuRoC's cam0 (so the built-in flight looks
/// into its room); the planted errors are added on top.
ovton::core::CameraCalib phone_like_camera() {
  ovton::core::CameraCalib c;
  c.width = 640;
  c.height = 480;
  c.rate_hz = 30;
  c.intrinsics << 500, 500, 320, 240;
  c.dist_coeffs.setZero();
  c.T_BC.setIdentity();
  c.T_BC.block<3, 3>(0, 0) << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  return c;
}

TEST(Calibrate, RecoversPlantedRotationFocalOffsetAndReadoutOfARender) {
  ovtest::TempDir dir;
  ovton::sim::SimOptions o;
  o.out_dir = dir / "sim";
  o.duration_s = 10.0;
  o.agility = 1.0;
  o.cam = phone_like_camera();
  o.extrinsic_rot = Eigen::Vector3d(6, -4, 8) * kDeg;
  o.focal_error = 0.10;
  o.td.td0_s = 0.070;
  o.readout_s = 0.016;
  ovton::sim::write_simulation(o);
  std::filesystem::remove(dir / "sim/mav0/cam0/sensor.yaml");
  std::filesystem::remove(dir / "sim/mav0/imu0/sensor.yaml");

  const ovton::core::Dataset d = ovton::core::load_euroc_streams(o.out_dir);
  const ovton::msckf::CalibResult c = ovton::msckf::calibrate_recording(d, 0.0, 0.0, {});
  std::cout << c.summary() << "\n";

  const Eigen::Matrix3d R_true = ovton::core::so3_exp(o.extrinsic_rot) * o.cam.T_BC.block<3, 3>(0, 0);
  const Eigen::Vector3d rot_err = ovton::core::so3_log(c.R_IC * R_true.transpose());
  const double f_true = 500 * (1 + o.focal_error);
  const double td_true = o.td.td0_s + 0.5 * o.readout_s; // the fit's t_d belongs to the middle row
  std::cout << "[ measured ] rotation error " << rot_err.norm() / kDeg << " deg (" << rot_err.transpose() / kDeg
            << "), focal " << c.focal_px << " vs " << f_true << " px, t_d " << c.td_s * 1e3 << " vs " << td_true * 1e3
            << " ms, readout " << c.readout_s * 1e3 << " vs " << o.readout_s * 1e3 << " ms\n";
  EXPECT_LT(rot_err.norm(), 1.0 * kDeg);
  EXPECT_LT(std::abs(c.focal_px / f_true - 1), 0.03);
  EXPECT_LT(std::abs(c.td_s - td_true), 0.002);
  EXPECT_LT(std::abs(c.readout_s - o.readout_s), 0.005);
  // Against its own σ: an error beyond 3σ would make the σ the filter starts from a lie.
  for (int i = 0; i < 3; ++i)
    EXPECT_LT(std::abs(rot_err(i)), 3 * c.sigma_rot_rad(i) + 0.05 * kDeg) << "axis " << i;
  EXPECT_LT(std::abs(c.focal_px - f_true), 3 * c.sigma_focal_px);
  EXPECT_LT(std::abs(c.td_s - td_true), 3 * c.sigma_td_s);
  EXPECT_LT(std::abs(c.readout_s - o.readout_s), 3 * c.sigma_readout_s);
  EXPECT_GT(c.pairs_used, 200);
}

TEST(Calibrate, ReadsTheRealPhoneRecordingAndGivesFiniteEstimates) {
  const std::string phone = ovtest::shared_data() + "/android_phone_walk";
  if (!std::filesystem::is_directory(phone))
    GTEST_SKIP() << phone << " not found";
  const ovton::core::Dataset d = ovton::core::load_euroc_streams(phone);
  EXPECT_EQ(d.images.size(), 1571u);
  EXPECT_GT(d.imu_calib.rate_hz, 150.0); // arrival-time stamps: the median spacing stands for the rate
  const ovton::msckf::CalibResult c = ovton::msckf::calibrate_recording(d, 0.0, 15.0, {});
  std::cout << c.summary() << "\n";
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  for (double v :
       {c.td_s, c.sigma_td_s, c.focal_px, c.sigma_focal_px, c.readout_s, c.sigma_readout_s, c.sigma_rot_rad.norm()})
    EXPECT_TRUE(std::isfinite(v));
  EXPECT_GT(c.sigma_td_s, 0.0);
  EXPECT_LT(std::abs(c.td_s), 0.2);
  EXPECT_GT(c.pairs_used, 100);
}

} // namespace
