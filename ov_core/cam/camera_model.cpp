#include "ov_core/cam/camera_model.h"
#include "ov_core/types/errors.h"
#include <Eigen/LU>
#include <cmath>

namespace ovton::core {

CameraModel::CameraModel(const CameraCalib &calib) : calib_(calib) {
  if (calib_.width <= 0 || calib_.height <= 0)
    throw UsageError("CameraModel: image size must be positive");
  if (!(calib_.intrinsics(0) > 0) || !(calib_.intrinsics(1) > 0))
    throw UsageError("CameraModel: focal lengths must be positive");
}

Eigen::Vector2d CameraModel::distort_normalized(const Eigen::Vector2d &xn, Eigen::Matrix2d *J) const {
  const Eigen::Vector4d &k = calib_.dist_coeffs;
  const double x = xn.x(), y = xn.y();
  if (calib_.distortion == DistortionModel::RadTan) {
    const double r2 = x * x + y * y;
    const double radial = 1.0 + k(0) * r2 + k(1) * r2 * r2;
    const double p1 = k(2), p2 = k(3);
    Eigen::Vector2d xd(x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                       y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y);
    if (J) {
      const double dr = k(0) + 2.0 * k(1) * r2; // d(radial)/d(r2)
      (*J)(0, 0) = radial + 2.0 * x * x * dr + 2.0 * p1 * y + 6.0 * p2 * x;
      (*J)(0, 1) = 2.0 * x * y * dr + 2.0 * p1 * x + 2.0 * p2 * y;
      (*J)(1, 0) = (*J)(0, 1);
      (*J)(1, 1) = radial + 2.0 * y * y * dr + 6.0 * p1 * y + 2.0 * p2 * x;
    }
    return xd;
  }
  // Equidistant (Kalibr): theta_d = theta (1 + k1 theta^2 + ... + k4 theta^8), xd = theta_d / r * x.
  const double r = std::sqrt(x * x + y * y);
  if (r < 1e-10) {
    if (J)
      J->setIdentity();
    return xn;
  }
  const double th = std::atan(r), th2 = th * th;
  const double poly = 1.0 + th2 * (k(0) + th2 * (k(1) + th2 * (k(2) + th2 * k(3))));
  const double thd = th * poly;
  const double s = thd / r;
  if (J) {
    const double dthd_dth = 1.0 + th2 * (3.0 * k(0) + th2 * (5.0 * k(1) + th2 * (7.0 * k(2) + th2 * 9.0 * k(3))));
    const double dthd_dr = dthd_dth / (1.0 + r * r);
    const double ds_dr = (dthd_dr * r - thd) / (r * r);
    const Eigen::Vector2d dr_dx(x / r, y / r);
    *J = s * Eigen::Matrix2d::Identity() + xn * (ds_dr * dr_dx.transpose());
  }
  return s * xn;
}

Eigen::Vector2d CameraModel::distort(const Eigen::Vector2d &xn, Eigen::Matrix2d *J) const {
  const Eigen::Vector2d xd = distort_normalized(xn, J);
  if (J) {
    J->row(0) *= fu();
    J->row(1) *= fv();
  }
  return Eigen::Vector2d(fu() * xd.x() + cu(), fv() * xd.y() + cv());
}

Eigen::Matrix<double, 2, 8> CameraModel::intrinsics_jacobian(const Eigen::Vector2d &xn) const {
  const Eigen::Vector2d xd = distort_normalized(xn);
  Eigen::Matrix<double, 2, 8> J = Eigen::Matrix<double, 2, 8>::Zero();
  J(0, 0) = xd.x();
  J(1, 1) = xd.y();
  J(0, 2) = 1.0;
  J(1, 3) = 1.0;
  const double x = xn.x(), y = xn.y();
  Eigen::Matrix<double, 2, 4> dxd; // d(distorted normalised)/d(d0..d3)
  if (calib_.distortion == DistortionModel::RadTan) {
    const double r2 = x * x + y * y;
    dxd << x * r2, x * r2 * r2, 2.0 * x * y, r2 + 2.0 * x * x, //
        y * r2, y * r2 * r2, r2 + 2.0 * y * y, 2.0 * x * y;
  } else {
    const double r = std::sqrt(x * x + y * y);
    if (r < 1e-10)
      return J;
    const double th = std::atan(r);
    const double t3 = th * th * th, t5 = t3 * th * th, t7 = t5 * th * th, t9 = t7 * th * th;
    dxd << x / r * t3, x / r * t5, x / r * t7, x / r * t9, //
        y / r * t3, y / r * t5, y / r * t7, y / r * t9;
  }
  J.block<1, 4>(0, 4) = fu() * dxd.row(0);
  J.block<1, 4>(1, 4) = fv() * dxd.row(1);
  return J;
}

Eigen::Vector2d CameraModel::undistort(const Eigen::Vector2d &uv) const {
  const Eigen::Vector2d xd((uv.x() - cu()) / fu(), (uv.y() - cv()) / fv());
  Eigen::Vector2d xn = xd;
  for (int it = 0; it < 30; ++it) {
    Eigen::Matrix2d J;
    const Eigen::Vector2d err = distort_normalized(xn, &J) - xd;
    const Eigen::Vector2d step = J.inverse() * err; // 2x2: closed form
    xn -= step;
    if (step.squaredNorm() < 1e-26)
      break;
  }
  return xn;
}

bool CameraModel::project(const Eigen::Vector3d &p_C, Eigen::Vector2d &uv, Eigen::Matrix<double, 2, 3> *J,
                          double min_depth) const {
  if (!(p_C.z() > min_depth))
    return false;
  const double iz = 1.0 / p_C.z();
  const Eigen::Vector2d xn(p_C.x() * iz, p_C.y() * iz);
  Eigen::Matrix2d Jd;
  uv = distort(xn, J ? &Jd : nullptr);
  if (J) {
    Eigen::Matrix<double, 2, 3> Jn;
    Jn << iz, 0.0, -xn.x() * iz, 0.0, iz, -xn.y() * iz;
    *J = Jd * Jn;
  }
  return true;
}

Eigen::Vector3d CameraModel::unproject(const Eigen::Vector2d &uv) const {
  const Eigen::Vector2d xn = undistort(uv);
  return Eigen::Vector3d(xn.x(), xn.y(), 1.0).normalized();
}

} // namespace ovton::core
