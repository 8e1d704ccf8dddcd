#pragma once
// The MSCKF camera measurement of one feature in one clone, in undistorted normalised coordinates, and its Jacobians
// in the error-state convention of ov_msckf_ton/state/state.h (R_WB = Exp(δθ)·R̂_WB, p = p̂ + δp).
#include "ov_core/math/so3.h"

#include <Eigen/Core>

namespace ov_msckf_ton {

/// Jacobians of z = π(p_C) w.r.t. the clone's [δθ δp], the world feature position p_f and the camera–IMU
/// extrinsics [δθ_BC δp_BC] (R_BC = Exp(δθ_BC)·R̂_BC).
struct CloneMeasurementJacobians {
  Eigen::Matrix<double, 2, 3> H_theta;
  Eigen::Matrix<double, 2, 3> H_p;
  Eigen::Matrix<double, 2, 3> H_f;
  Eigen::Matrix<double, 2, 3> H_ext_theta;
  Eigen::Matrix<double, 2, 3> H_ext_p;
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
    J->H_theta = J->H_f * ov_core::skew(p_f - p_WB);
    J->H_p = -J->H_f;
    const Eigen::Matrix<double, 2, 3> dz_dpB = dz_dpc * R_BC.transpose();
    J->H_ext_theta = dz_dpB * ov_core::skew(p_B - p_BC);
    J->H_ext_p = -dz_dpB;
  }
  return true;
}

} // namespace ov_msckf_ton
