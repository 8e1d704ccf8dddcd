// Kalibr calibration files as users bring them: the TUM-VI camchain (pinhole + equidistant / Kannala-Brandt, 512x512
// fisheye, T_cam_imu) read into the camera model, found as a bag's calibration, and written back by ovton.
#include "ov_core/cam/camera_model.h"
#include "ov_core/io/bag_calibration.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/kalibr_writer.h"
#include "test_util.h"

#include <fstream>
#include <gtest/gtest.h>
#include <iterator>
#include <opencv2/core/persistence.hpp>

using namespace ovton::core;

namespace {

// TUM-VI cam0 (512x512) and its IMU as the dataset publishes them (Kalibr's camchain-imucam / imu format).
const char *kTumViCamchain = R"(cam0:
  T_cam_imu:
  - [-0.9995250378696743, 0.029615343885863205, -0.008522328211654736, 0.04727988224914392]
  - [0.0075019185074052044, -0.03439736061393144, -0.9993800792498829, -0.047443232143367084]
  - [-0.02989013031643309, -0.998969345370175, 0.03415885127385616, -0.0681999605066297]
  - [0.0, 0.0, 0.0, 1.0]
  camera_model: pinhole
  distortion_coeffs: [0.0034823894022493434, 0.0007150348452162257, -0.0020532361418706202, 0.00020293673591811182]
  distortion_model: equidistant
  intrinsics: [190.97847715128717, 190.9733070521226, 254.93170605935475, 256.8974428996504]
  resolution: [512, 512]
  rostopic: /cam0/image_raw
  timeshift_cam_imu: 0.0
)";
const char *kTumViImu = R"(imu0:
  T_i_b:
  - [1.0, 0.0, 0.0, 0.0]
  - [0.0, 1.0, 0.0, 0.0]
  - [0.0, 0.0, 1.0, 0.0]
  - [0.0, 0.0, 0.0, 1.0]
  accelerometer_noise_density: 0.0028
  accelerometer_random_walk: 0.00086
  gyroscope_noise_density: 0.00016
  gyroscope_random_walk: 2.2e-05
  model: calibrated
  rostopic: /imu0
  time_offset: 0.0
  update_rate: 200.0
)";

} // namespace

TEST(Kalibr, TumViCamchainIsEquidistant) {
  ovtest::TempDir d;
  ovtest::write_text(d / "camchain-imucam.yaml", kTumViCamchain);
  const KalibrCamera k = load_kalibr_camchain(d / "camchain-imucam.yaml");
  EXPECT_EQ(k.cam.distortion, DistortionModel::Equidistant);
  EXPECT_EQ(k.cam.width, 512);
  EXPECT_DOUBLE_EQ(k.cam.intrinsics(0), 190.97847715128717);
  EXPECT_DOUBLE_EQ(k.cam.dist_coeffs(3), 0.00020293673591811182);
  EXPECT_EQ(k.rostopic, "/cam0/image_raw");
  // T_BC is the inverse of Kalibr's T_cam_imu: the camera sits ~7 cm from the IMU and looks along body −y.
  EXPECT_NEAR((k.cam.T_BC.block<3, 1>(0, 3).norm()), 0.0957, 1e-3);
  EXPECT_NEAR((k.cam.T_BC.block<3, 3>(0, 0) * Eigen::Vector3d::UnitZ()).y(), -0.999, 1e-3);

  // The model projects and unprojects consistently over the fisheye image out to 80 deg off axis (the equidistant
  // model reaches past 90 deg; a pinhole-normalised point cannot).
  const CameraModel cam(k.cam);
  int checked = 0;
  for (double th = 0.0; th < 80.0 * M_PI / 180.0; th += 0.1)
    for (double phi = 0.0; phi < 2 * M_PI; phi += 0.5) {
      const Eigen::Vector3d ray(std::sin(th) * std::cos(phi), std::sin(th) * std::sin(phi), std::cos(th));
      Eigen::Vector2d uv;
      ASSERT_TRUE(cam.project(ray, uv));
      // Kannala-Brandt: the distance from the principal point grows with the angle (theta_d ~ theta), not tan.
      const double r = std::hypot((uv.x() - cam.cu()) / cam.fu(), (uv.y() - cam.cv()) / cam.fv());
      EXPECT_NEAR(r, th, 0.02 * th + 1e-9);
      if (!cam.in_image(uv))
        continue;
      EXPECT_LT((cam.unproject(uv) - ray).norm(), 1e-9) << "theta " << th << " phi " << phi;
      ++checked;
    }
  EXPECT_GT(checked, 100);
}

TEST(Kalibr, TumViFilesBesideABagAreFound) {
  ovtest::TempDir d;
  ovtest::write_text(d / "camchain-imucam-room1.yaml", kTumViCamchain);
  ovtest::write_text(d / "imu-room1.yaml", kTumViImu);
  const BagCalibration c = resolve_bag_calibration(d / "room1.bag", {});
  EXPECT_EQ(c.cam.distortion, DistortionModel::Equidistant);
  EXPECT_EQ(c.imu.rate_hz, 200.0);
  EXPECT_EQ(c.imu.gyro_noise_density, 0.00016);
  EXPECT_EQ(c.cam_topic_hint, "/cam0/image_raw");
  EXPECT_EQ(c.imu_topic_hint, "/imu0");
  // Given explicitly, in either order.
  const BagCalibration e =
      resolve_bag_calibration(d / "other.bag", {d / "imu-room1.yaml", d / "camchain-imucam-room1.yaml"});
  EXPECT_EQ(e.cam.intrinsics, c.cam.intrinsics);
  // Nothing beside another bag: the error names the bag.
  ovtest::expect_data_error([&] { resolve_bag_calibration(d / "sub/none.bag", {}); }, "none.bag", 0, "no calibration");
  // Two camera files: refused.
  EXPECT_THROW(
      resolve_bag_calibration(d / "x.bag", {d / "camchain-imucam-room1.yaml", d / "camchain-imucam-room1.yaml"}),
      UsageError);
}

TEST(Kalibr, WrittenFilesReadBack) {
  ovtest::TempDir d;
  ovtest::write_text(d / "in.yaml", kTumViCamchain);
  const KalibrCamera k = load_kalibr_camchain(d / "in.yaml");
  write_kalibr_camchain(d / "out.yaml", k.cam, 0.0125, "/left");
  const KalibrCamera b = load_kalibr_camchain(d / "out.yaml");
  EXPECT_EQ(b.cam.intrinsics, k.cam.intrinsics); // 17 significant digits: the same doubles
  EXPECT_EQ(b.cam.dist_coeffs, k.cam.dist_coeffs);
  EXPECT_EQ(b.cam.distortion, k.cam.distortion);
  EXPECT_LT((b.cam.T_BC - k.cam.T_BC).norm(), 1e-14);
  EXPECT_EQ(b.timeshift_cam_imu_s, 0.0125);
  EXPECT_EQ(b.rostopic, "/left");
  ovtest::write_text(d / "imu_in.yaml", kTumViImu);
  const KalibrImu i = load_kalibr_imu(d / "imu_in.yaml");
  write_kalibr_imu(d / "imu_out.yaml", i.imu, "/imu0");
  const KalibrImu j = load_kalibr_imu(d / "imu_out.yaml");
  EXPECT_EQ(j.imu.accel_random_walk, i.imu.accel_random_walk);
  EXPECT_EQ(j.imu.rate_hz, 200.0);
}

// OpenVINS reads a Kalibr camchain with OpenCV's FileStorage, whose YAML parser is stricter than yaml-cpp: the file
// ovton writes (calibrate, export) must parse there too, with T_cam_imu as four rows of four, once the "%YAML:1.0"
// line OpenCV wants first is added (as OpenVINS's own files have it; Kalibr's, like ours, lack it, and Python's yaml
// refuses it).
TEST(Kalibr, WrittenCamchainParsesWithOpenCvFileStorage) {
  ovtest::TempDir d;
  ovtest::write_text(d / "in.yaml", kTumViCamchain);
  const KalibrCamera k = load_kalibr_camchain(d / "in.yaml");
  write_kalibr_camchain(d / "out.yaml", k.cam, 0.0125, "/left");
  std::ifstream in(d / "out.yaml");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  cv::FileStorage fs;
  ASSERT_NO_THROW(fs.open("%YAML:1.0\n" + text, cv::FileStorage::READ | cv::FileStorage::MEMORY));
  ASSERT_TRUE(fs.isOpened());
  const cv::FileNode T = fs["cam0"]["T_cam_imu"];
  ASSERT_TRUE(T.isSeq());
  ASSERT_EQ(T.size(), 4u);
  const Eigen::Matrix4d T_CI = k.cam.T_BC.inverse();
  for (int r = 0; r < 4; ++r) {
    ASSERT_EQ(T[r].size(), 4u);
    for (int c = 0; c < 4; ++c)
      EXPECT_NEAR(static_cast<double>(T[r][c]), T_CI(r, c), 1e-12) << r << "," << c;
  }
  EXPECT_EQ(static_cast<std::string>(fs["cam0"]["distortion_model"]), "equidistant");
  EXPECT_DOUBLE_EQ(static_cast<double>(fs["cam0"]["timeshift_cam_imu"]), 0.0125);
}
