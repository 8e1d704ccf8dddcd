// Camera model: projection / undistortion round trip and the analytic Jacobians against finite differences.
#include "fd_check.h"
#include "ov_core/cam/camera_model.h"
#include "ov_sim/euroc_calib.h"

#include <gtest/gtest.h>

using namespace ovton::core;

namespace {
CameraCalib equidistant_calib() {
  CameraCalib c = ovton::sim::euroc_cam0_calib();
  c.distortion = DistortionModel::Equidistant;
  c.dist_coeffs << -0.01, 0.02, -0.005, 0.001;
  return c;
}
} // namespace

TEST(SimCameraModel, UndistortInvertsDistortAcrossTheImage) {
  for (const CameraCalib &c : {ovton::sim::euroc_cam0_calib(), equidistant_calib()}) {
    CameraModel cam(c);
    for (int v = 0; v < c.height; v += 37)
      for (int u = 0; u < c.width; u += 41) {
        const Eigen::Vector2d uv(u, v);
        const Eigen::Vector3d ray = cam.unproject(uv);
        Eigen::Vector2d back;
        ASSERT_TRUE(cam.project(ray, back));
        EXPECT_LT((back - uv).norm(), 1e-6) << "pixel " << u << "," << v << " " << to_string(c.distortion);
      }
  }
}

TEST(SimCameraModel, ProjectionJacobianMatchesFiniteDifferences) {
  for (const CameraCalib &c : {ovton::sim::euroc_cam0_calib(), equidistant_calib()}) {
    CameraModel cam(c);
    for (const Eigen::Vector3d &p :
         {Eigen::Vector3d(0.3, -0.2, 1.5), Eigen::Vector3d(-0.9, 0.5, 1.2), Eigen::Vector3d(0.01, 0.02, 3.0)}) {
      Eigen::Vector2d uv;
      Eigen::Matrix<double, 2, 3> J;
      ASSERT_TRUE(cam.project(p, uv, &J));
      const Eigen::MatrixXd num = ovtest::numeric_jacobian(
          [&](const Eigen::Vector3d &q) {
            Eigen::Vector2d z;
            cam.project(q, z);
            return z;
          },
          p, 1e-6);
      for (int i = 0; i < 3; ++i)
        EXPECT_LT((num.col(i) - J.col(i)).norm(), 1e-4 * (1.0 + num.col(i).norm()))
            << to_string(c.distortion) << " col " << i;
    }
  }
}

TEST(SimCameraModel, PointsBehindTheCameraDoNotProject) {
  CameraModel cam(ovton::sim::euroc_cam0_calib());
  Eigen::Vector2d uv(-7, -7);
  EXPECT_FALSE(cam.project(Eigen::Vector3d(0.1, 0.1, -1.0), uv));
  EXPECT_EQ(uv, Eigen::Vector2d(-7, -7));
}
