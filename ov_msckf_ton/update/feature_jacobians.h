#pragma once
// The MSCKF camera measurement of one feature in one clone, in undistorted normalised coordinates, and its Jacobians
// in the error-state convention of ov_msckf_ton/state/state.h (R_WB = Exp(δθ)·R̂_WB, p = p̂ + δp).
#include "ov_core/math/so3.h"
#include "ov_msckf_ton/state/state.h"

#include <Eigen/Core>

namespace ovton::msckf {

/// Jacobians of z = π(p_C) w.r.t. the clone's [δθ δp], the world feature position p_f and the camera–IMU
/// extrinsics [δθ_BC δp_BC] (R_BC = Exp(δθ_BC)·R̂_BC).
struct CloneMeasurementJacobians {
  Eigen::Matrix<double, 2, 3> H_theta;
  Eigen::Matrix<double, 2, 3> H_p;
  Eigen::Matrix<double, 2, 3> H_f;
  Eigen::Matrix<double, 2, 3> H_ext_theta;
  Eigen::Matrix<double, 2, 3> H_ext_p;
  static CloneMeasurementJacobians zero() {
    CloneMeasurementJacobians j;
    j.H_theta.setZero();
    j.H_p.setZero();
    j.H_f.setZero();
    j.H_ext_theta.setZero();
    j.H_ext_p.setZero();
    return j;
  }
};

/// Projects the world point p_f into the camera of a clone:
///   p_B = R_WBᵀ (p_f − p_WB),   p_C = R_BCᵀ (p_B − p_BC),   z = (x/z, y/z).
/// With R_WB = Exp(δθ)·R̂_WB, R_WBᵀ ≈ R̂_WBᵀ (I − [δθ]×), so p_B ≈ p̂_B + R̂_WBᵀ [p_f − p̂_WB]× δθ and
///   ∂p_C/∂δθ = R_BCᵀ R_WBᵀ [p_f − p_WB]×,   ∂p_C/∂δp = −R_BCᵀ R_WBᵀ,   ∂p_C/∂p_f = R_BCᵀ R_WBᵀ,
///   ∂z/∂p_C = [1/z 0 −x/z²; 0 1/z −y/z²].
/// With R_BC = Exp(δθ_BC)·R̂_BC, R_BCᵀ ≈ R̂_BCᵀ (I − [δθ_BC]×):
///   ∂p_C/∂δθ_BC = R_BCᵀ [p_B − p_BC]×,   ∂p_C/∂δp_BC = −R_BCᵀ.
/// Returns false (outputs untouched except p_C) when the point is not in front of the camera (z <= min_z), where
/// the projection and its Jacobian are meaningless.
inline bool project_in_clone(const Eigen::Matrix3d &R_WB, const Eigen::Vector3d &p_WB, const Eigen::Matrix3d &R_BC,
                             const Eigen::Vector3d &p_BC, const Eigen::Vector3d &p_f, Eigen::Vector2d &z,
                             Eigen::Vector3d *p_C_out = nullptr, CloneMeasurementJacobians *J = nullptr,
                             double min_z = 1e-9) {
  const Eigen::Vector3d p_B = R_WB.transpose() * (p_f - p_WB);
  const Eigen::Vector3d p_C = R_BC.transpose() * (p_B - p_BC);
  if (p_C_out)
    *p_C_out = p_C;
  if (!(p_C.z() > min_z))
    return false;
  const double iz = 1.0 / p_C.z();
  z = Eigen::Vector2d(p_C.x() * iz, p_C.y() * iz);
  if (J) {
    Eigen::Matrix<double, 2, 3> dz_dpc;
    dz_dpc << iz, 0.0, -p_C.x() * iz * iz, 0.0, iz, -p_C.y() * iz * iz;
    const Eigen::Matrix3d R_CW = R_BC.transpose() * R_WB.transpose();
    J->H_f = dz_dpc * R_CW;
    J->H_theta = J->H_f * ovton::core::skew(p_f - p_WB);
    J->H_p = -J->H_f;
    const Eigen::Matrix<double, 2, 3> dz_dpB = dz_dpc * R_BC.transpose();
    J->H_ext_theta = dz_dpB * ovton::core::skew(p_B - p_BC);
    J->H_ext_p = -dz_dpB;
  }
  return true;
}

/// The normalised image velocity [1/s] of a point at p_W seen from a camera on the body at (R_WB, p_WB) that moves
/// with `m`: with p_B = R_WBᵀ (p_W − p_WB) and q = ṗ_B = −ω × p_B − R_WBᵀ v,
///   p_C = R_BCᵀ (p_B − p_BC),   d = ṗ_C = R_BCᵀ q,   V = (d_xy − (p_C,xy / z)·d_z) / z.
/// J (optional): V's Jacobians in the slots of CloneMeasurementJacobians, (ω, v) held fixed (they are not state
/// variables). With the state's perturbations (as project_in_clone, a = p_W − p_WB):
///   ∂p_C/∂δθ = R_BCᵀ R_WBᵀ [a]×,        ∂d/∂δθ = R_BCᵀ (−[ω]× R_WBᵀ [a]× − R_WBᵀ [v]×)
///   ∂p_C/∂δp = −R_BCᵀ R_WBᵀ,           ∂d/∂δp = R_BCᵀ [ω]× R_WBᵀ        (p_f: the negatives)
///   ∂p_C/∂δθ_BC = R_BCᵀ [p_B − p_BC]×,  ∂d/∂δθ_BC = R_BCᵀ [q]×,   ∂p_C/∂δp_BC = −R_BCᵀ,  ∂d/∂δp_BC = 0
///   ∂V/∂p_C = [−d_z/z² 0 −d_x/z² + 2 x d_z/z³; 0 −d_z/z² −d_y/z² + 2 y d_z/z³],   ∂V/∂d = ∂π/∂p_C.
/// False behind the camera.
inline bool predicted_image_velocity(const Eigen::Matrix3d &R_WB, const Eigen::Vector3d &p_WB,
                                     const Eigen::Matrix3d &R_BC, const Eigen::Vector3d &p_BC,
                                     const Eigen::Vector3d &p_W, const BodyMotion &m, Eigen::Vector2d &vel_xy,
                                     CloneMeasurementJacobians *J = nullptr) {
  const Eigen::Vector3d p_B = R_WB.transpose() * (p_W - p_WB);
  const Eigen::Vector3d p_C = R_BC.transpose() * (p_B - p_BC);
  if (!(p_C.z() > 1e-9))
    return false;
  const Eigen::Vector3d q = -m.w_B.cross(p_B) - R_WB.transpose() * m.v_W;
  const Eigen::Vector3d d = R_BC.transpose() * q;
  const double iz = 1.0 / p_C.z(), x = p_C.x(), y = p_C.y();
  vel_xy = Eigen::Vector2d(d.x() - x * iz * d.z(), d.y() - y * iz * d.z()) * iz;
  if (J) {
    const double iz2 = iz * iz, iz3 = iz2 * iz;
    Eigen::Matrix<double, 2, 3> dV_dpc, dV_dd;
    dV_dpc << -d.z() * iz2, 0.0, -d.x() * iz2 + 2.0 * x * d.z() * iz3, //
        0.0, -d.z() * iz2, -d.y() * iz2 + 2.0 * y * d.z() * iz3;
    dV_dd << iz, 0.0, -x * iz2, 0.0, iz, -y * iz2;
    const Eigen::Matrix3d R_CB = R_BC.transpose(), R_BW = R_WB.transpose();
    const Eigen::Matrix3d W = ovton::core::skew(m.w_B);
    const Eigen::Matrix<double, 2, 3> A = dV_dpc * R_CB, B = dV_dd * R_CB; // per ∂p_B and per ∂q
    J->H_f = A * R_BW - B * W * R_BW;
    J->H_p = -J->H_f;
    J->H_theta = A * R_BW * ovton::core::skew(p_W - p_WB) -
                 B * (W * R_BW * ovton::core::skew(p_W - p_WB) + R_BW * ovton::core::skew(m.v_W));
    J->H_ext_theta = dV_dpc * R_CB * ovton::core::skew(p_B - p_BC) + dV_dd * R_CB * ovton::core::skew(q);
    J->H_ext_p = -dV_dpc * R_CB;
  }
  return true;
}

} // namespace ovton::msckf
