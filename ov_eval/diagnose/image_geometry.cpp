#include "ov_eval/diagnose/image_geometry.h"

#include <Eigen/LU>

namespace ovton::eval::diag {

Eigen::Matrix<double, 2, 3> rot_flow(double x, double y) {
  Eigen::Matrix<double, 2, 3> B;
  B << x * y, -(1 + x * x), y, 1 + y * y, -x * y, -x;
  return B;
}

ErrorDirs error_dirs(const ovton::core::CameraModel *cam, const Eigen::Vector2d &x) {
  const Eigen::Vector2d k1 = x.squaredNorm() * x;
  if (!cam)
    return {x, k1};
  Eigen::Matrix2d Jd;
  const Eigen::Vector2d xd = cam->distort_normalized(x, &Jd);
  const Eigen::PartialPivLU<Eigen::Matrix2d> lu(Jd);
  return {lu.solve(xd), lu.solve(k1)};
}

} // namespace ovton::eval::diag
