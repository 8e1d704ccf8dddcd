#pragma once
// How the candidate effects move a normalised image point, shared by the residual and the rate designs.
#include "ov_core/cam/camera_model.h"

#include <Eigen/Core>

namespace ovton::eval::diag {

/// Rotational image flow of a normalised point per unit camera rotation (columns: rotation about x, y, z).
Eigen::Matrix<double, 2, 3> rot_flow(double x, double y);

/// The shifts of an undistorted normalised point x per unit relative focal error ε and per unit δk1. Both act on the
/// distorted point and the filter undistorts, so each is the distorted change mapped through the inverse of the
/// distortion's Jacobian: J_d⁻¹·x_d and J_d⁻¹·|x|²·x (x and |x|²·x without a camera model).
struct ErrorDirs {
  Eigen::Vector2d focal, k1;
};
ErrorDirs error_dirs(const ovton::core::CameraModel *cam, const Eigen::Vector2d &x);
inline Eigen::Vector2d focal_dir(const ovton::core::CameraModel *cam, const Eigen::Vector2d &x) {
  return error_dirs(cam, x).focal;
}

} // namespace ovton::eval::diag
