// The gyro's rotation prior for KLT: the integration (clock convention t_imu = t_cam + t_d, frames) against closed
// forms, and LK started from it finding a turn its pyramid alone cannot.
#include "ov_core/cam/camera_model.h"
#include "ov_core/math/so3.h"
#include "ov_core/track/gyro_prior.h"
#include "ov_core/track/track_klt.h"
#include "track_test_util.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <map>

using namespace ovton::core;

namespace {

constexpr int64_t kT0 = 1403715273262142976LL; // a real EuRoC stamp
constexpr int64_t kDt = 50000000LL;            // 20 Hz images

/// Readings at 200 Hz, 1.7 ms out of step with the images, over [kT0 - 1 s, kT0 + 1 s], rate w(t) [IMU frame].
template <class Rate> std::vector<ImuData> gyro_log(Rate rate) {
  std::vector<ImuData> imu;
  for (int64_t t = kT0 - 1000000000LL + 1700000LL; t < kT0 + 1000000000LL; t += 5000000LL) {
    ImuData m;
    m.t_imu_ns = t;
    m.wm = rate(t);
    imu.push_back(m);
  }
  return imu;
}

} // namespace

TEST(GyroRotationPrior, IntegratesTheRateOverTheImagesSpanShiftedByTheOffset) {
  // A rate ramping about z: the turn between two images depends on where t_d puts them in the IMU log.
  const double c = 4.0; // rad/s^2
  const int64_t ts = kT0 - 200000000LL;
  const auto imu = gyro_log([&](int64_t t) { return Eigen::Vector3d(0, 0, c * (t - ts) * 1e-9); });
  for (double td : {0.0, 0.012, -0.020}) {
    const GyroRotationPrior prior(imu, Eigen::Matrix3d::Identity(), td);
    const int64_t t0 = kT0, t1 = kT0 + kDt;
    const auto R = prior.camera_rotation(t0, t1);
    ASSERT_TRUE(R.has_value());
    const double a = (t0 - ts) * 1e-9 + td, b = (t1 - ts) * 1e-9 + td;
    const double angle = 0.5 * c * (b * b - a * a); // the camera turns by +angle; bearings turn back by it
    EXPECT_NEAR(so3_log(*R).z(), -angle, 1e-9) << "t_d " << td;
    EXPECT_NEAR(so3_log(*R).head<2>().norm(), 0.0, 1e-12);
  }
  const GyroRotationPrior prior(imu, Eigen::Matrix3d::Identity(), 0.0);
  EXPECT_FALSE(prior.camera_rotation(kT0 + kDt, kT0).has_value()) << "backwards";
  EXPECT_FALSE(prior.camera_rotation(kT0 + 900000000LL, kT0 + 1100000000LL).has_value()) << "past the log";
}

TEST(TrackKLT, GyroPriorFindsATurnTheFlatPyramidCannot) {
  // The camera turns 0.087 rad about its y axis (40 px at EuRoC's focal length) and 0.02 rad about z in one image;
  // the IMU, mounted as on EuRoC, measures that turn. LK on a single pyramid level (21 px window) cannot reach it
  // from where the points were; from where the gyro says they went it can.
  const CameraCalib calib = ovtest::pinhole_calib();
  const CameraModel camera(calib);
  const Eigen::Matrix3d R_c1c0 = so3_exp(Eigen::Vector3d(0, -0.087, 0.02));
  Eigen::Matrix3d K;
  K << camera.fu(), 0, camera.cu(), 0, camera.fv(), camera.cv(), 0, 0, 1;
  const Eigen::Matrix3d H = K * R_c1c0 * K.inverse();
  cv::Mat Hcv(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int col = 0; col < 3; ++col)
      Hcv.at<double>(r, col) = H(r, col);
  const cv::Mat img0 = ovtest::random_texture(calib.width, calib.height, 7);
  cv::Mat img1;
  cv::warpPerspective(img0, img1, Hcv, img0.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);

  const Eigen::Matrix3d R_IC = ovton::sim::euroc_cam0_calib().T_BC.block<3, 3>(0, 0);
  // Constant rate in the camera frame, w_C = log(R_c0c1) / dt, measured in the IMU frame.
  const Eigen::Vector3d w_I = R_IC * so3_log(R_c1c0.transpose()) / (kDt * 1e-9);
  const auto prior = std::make_shared<GyroRotationPrior>(gyro_log([&](int64_t) { return w_I; }), R_IC, 0.003);

  for (bool use_prior : {false, true}) {
    TrackKLTOptions opt;
    opt.pyr_levels = 0;
    opt.gyro_prior = use_prior;
    opt.use_ransac = false; // judge LK alone
    TrackKLT trk(camera, opt);
    trk.set_rotation_prior(prior);
    std::map<size_t, Eigen::Vector2d> first;
    for (const auto &f : trk.track(kT0, img0))
      first[f.id] = f.uv;
    int judged = 0, right = 0;
    for (const auto &f : trk.track(kT0 + kDt, img1)) {
      const auto it = first.find(f.id);
      if (it == first.end())
        continue;
      const Eigen::Vector2d expect = (H * it->second.homogeneous()).hnormalized();
      // Away from the reflected border, where the warp's content is not the turned scene.
      if (expect.x() < 40 || expect.y() < 40 || expect.x() > calib.width - 40 || expect.y() > calib.height - 40)
        continue;
      ++judged;
      right += (f.uv - expect).norm() < 0.5; // the turn also skews each window a little
    }
    // Without the prior most points are lost or land elsewhere; with it all but a few are found.
    const int expected_points = 60; // 200 detected, less those that leave the judged area
    if (use_prior) {
      EXPECT_GE(judged, expected_points);
      EXPECT_GE(right, 0.95 * judged) << right << " of " << judged;
    } else {
      EXPECT_LE(right, 0.2 * std::max(judged, expected_points)) << right << " of " << judged;
    }
  }
}
