#pragma once
// SO(3) helpers on Eigen types. Exp/Log map between rotation vectors and rotation matrices; Jr is the right
// Jacobian: Exp(phi + d) ≈ Exp(phi) Exp(Jr(phi) d).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace ovton::core {

inline Eigen::Matrix3d skew(const Eigen::Vector3d &w) {
  Eigen::Matrix3d S;
  S << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return S;
}

inline Eigen::Matrix3d so3_exp(const Eigen::Vector3d &phi) {
  const double th = phi.norm();
  const Eigen::Matrix3d K = skew(phi);
  if (th < 1e-7)
    return Eigen::Matrix3d::Identity() + K + 0.5 * K * K;
  return Eigen::Matrix3d::Identity() + std::sin(th) / th * K + (1 - std::cos(th)) / (th * th) * K * K;
}

inline Eigen::Vector3d so3_log(const Eigen::Matrix3d &R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

/// Right Jacobian of SO(3).
inline Eigen::Matrix3d so3_jr(const Eigen::Vector3d &phi) {
  const double th = phi.norm();
  const Eigen::Matrix3d K = skew(phi);
  if (th < 1e-5)
    return Eigen::Matrix3d::Identity() - 0.5 * K + K * K / 6.0;
  return Eigen::Matrix3d::Identity() - (1 - std::cos(th)) / (th * th) * K +
         (th - std::sin(th)) / (th * th * th) * K * K;
}

/// Inverse of the right Jacobian.
inline Eigen::Matrix3d so3_jr_inv(const Eigen::Vector3d &phi) {
  const double th = phi.norm();
  const Eigen::Matrix3d K = skew(phi);
  if (th < 1e-5)
    return Eigen::Matrix3d::Identity() + 0.5 * K + K * K / 12.0;
  return Eigen::Matrix3d::Identity() + 0.5 * K +
         (1.0 / (th * th) - (1 + std::cos(th)) / (2 * th * std::sin(th))) * K * K;
}

/// Rotation matrix -> unit Hamilton quaternion with w >= 0 (one representative of the double cover).
inline Eigen::Quaterniond to_quat(const Eigen::Matrix3d &R) {
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0)
    q.coeffs() *= -1;
  return q;
}

} // namespace ovton::core
