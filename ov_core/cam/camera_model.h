#pragma once
// Pinhole camera with radial-tangential (EuRoC/OpenCV k1 k2 p1 p2) or equidistant (Kalibr k1..k4) distortion.
// Shared by the simulator (rendering, feature projection) and the estimator (measurement model).
#include "ov_core/cam/camera_calib.h"
#include <Eigen/Core>

namespace ovton::core {

class CameraModel {
public:
  explicit CameraModel(const CameraCalib &calib);

  const CameraCalib &calib() const { return calib_; }
  int width() const { return calib_.width; }
  int height() const { return calib_.height; }
  double fu() const { return calib_.intrinsics(0); }
  double fv() const { return calib_.intrinsics(1); }
  double cu() const { return calib_.intrinsics(2); }
  double cv() const { return calib_.intrinsics(3); }

  /// Undistorted normalised point (x/z, y/z) -> distorted normalised point. J: d(distorted)/d(undistorted).
  Eigen::Vector2d distort_normalized(const Eigen::Vector2d &xn, Eigen::Matrix2d *J = nullptr) const;
  /// Undistorted normalised point -> distorted pixel. J: d(uv)/d(xn).
  Eigen::Vector2d distort(const Eigen::Vector2d &xn, Eigen::Matrix2d *J = nullptr) const;
  /// d(distorted pixel)/d[fu fv cu cv d0 d1 d2 d3] at the undistorted normalised point xn (online calibration).
  Eigen::Matrix<double, 2, 8> intrinsics_jacobian(const Eigen::Vector2d &xn) const;
  /// Distorted pixel -> undistorted normalised point, by Gauss-Newton on distort() (exact to ~1e-12 inside
  /// the image; distortion models have no closed-form inverse).
  Eigen::Vector2d undistort(const Eigen::Vector2d &uv) const;
  /// Camera-frame point -> distorted pixel. Returns false (uv untouched) when the point is not in front of
  /// the camera (z <= min_depth). J: d(uv)/d(p_C).
  bool project(const Eigen::Vector3d &p_C, Eigen::Vector2d &uv, Eigen::Matrix<double, 2, 3> *J = nullptr,
               double min_depth = 1e-6) const;
  /// Distorted pixel -> unit bearing in the camera frame.
  Eigen::Vector3d unproject(const Eigen::Vector2d &uv) const;
  /// True when the pixel lies inside the image with `border` pixels to spare (pixel centres at integers).
  bool in_image(const Eigen::Vector2d &uv, double border = 0.0) const {
    return uv.x() >= border - 0.5 && uv.y() >= border - 0.5 && uv.x() <= width() - 0.5 - border &&
           uv.y() <= height() - 0.5 - border;
  }

private:
  CameraCalib calib_;
};

} // namespace ovton::core
