#pragma once
// Stateless operations on a State's covariance: propagation, stochastic cloning, marginalisation, EKF update.
#include "ov_msckf_ton/state/state.h"

#include <vector>

namespace ovton::msckf {
namespace state_helper {

/// P_II <- Φ P_II Φᵀ + Q, cross terms P_IX <- Φ P_IX (the IMU block; t_d's model propagates its own block).
void propagate_covariance(State &s, const Eigen::Matrix<double, 15, 15> &Phi, const Eigen::Matrix<double, 15, 15> &Q);
/// The same with the IMU block also depending on the 12 constant IMU intrinsics at `cal_index` through Γ:
/// the IMU rows become A·P with A = [Φ at the IMU block, Γ at the intrinsics], and P_II = A P Aᵀ + Q.
void propagate_covariance(State &s, const Eigen::Matrix<double, 15, 15> &Phi, const Eigen::Matrix<double, 15, 15> &Q,
                          const Eigen::Matrix<double, 15, 12> &Gamma, int cal_index);

/// Clones the current IMU pose for the image stamped t_cam_ns (camera clock) at IMU time s.t_imu_ns.
/// In state-relevant mode the clone depends on t_d: the true image time is t̂_imu + δt_d, so
///   δθ_c = δθ + R̂ ω_B δt_d,   δp_c = δp + v_W δt_d   (ω_B bias-corrected body rate, v_W world velocity)
/// td_coupled = false gives the plain clone (δθ_c = δθ, δp_c = δp) used when t_d acts on the image plane instead.
/// The clone keeps (ω_B, v_W) as its motion in either case.
void clone(State &s, int64_t t_cam_ns, bool td_coupled, const Eigen::Vector3d &w_B, const Eigen::Vector3d &v_W);

/// Removes a clone and its rows/columns from the covariance.
void marginalize_clone(State &s, int64_t t_cam_ns);
/// Removes a SLAM landmark and its rows/columns from the covariance.
void marginalize_landmark(State &s, size_t id);

/// EKF update with a dense Jacobian H (m × dim), residual r = z − h(x̂), and isotropic noise sigma².
/// Keeps P symmetric; returns the Mahalanobis distance rᵀS⁻¹r.
double ekf_update(State &s, const Eigen::MatrixXd &H, const Eigen::VectorXd &r, double sigma2);
/// The same with a compact Jacobian: column j of Hc is state column cols[j], every other column of H is zero. Costs
/// O(n·|cols|·m + n²·m) instead of O(n³): the MSCKF and SLAM Jacobians involve the clones but not the landmarks
/// (or the reverse), so most of the state's columns are zero.
///
/// The extra noise ΔR of an update's rows under the reported covariance's track model (ekf_update): in the rows' own
/// basis (m × m), or seen through the Jacobian, G = HcᵀΔRHc (|cols| × |cols|) — what a caller has when it compressed
/// the rows after ΔR was known (K ΔR Kᵀ = P⁺GP⁺/σ⁴ since K = P⁺Hᵀ/σ² for the σ²I weight). Null: none.
struct ReportNoise {
  const Eigen::MatrixXd *rows = nullptr;
  const Eigen::MatrixXd *cols = nullptr;
  bool any() const { return rows || cols; }
};

/// Where the state keeps a separately reported covariance (State::P_report), it becomes the Joseph form of this
/// update's gain K (computed from P with the σ²I weight) under the noise the track-error model gives the rows,
/// σ²I + ΔR: P_r⁺ = (I − KH)P_r(I − KH)ᵀ + K(σ²I + ΔR)Kᵀ — the error covariance the weights that measured best
/// really leave. A ΔR without a reported covariance is refused.
double ekf_update(State &s, const std::vector<int> &cols, const Eigen::MatrixXd &Hc, const Eigen::VectorXd &r,
                  double sigma2, const ReportNoise &noise = {});

/// P restricted to the rows and columns `cols`, in that order.
Eigen::MatrixXd sub_covariance(const State &s, const std::vector<int> &cols);

/// Forces symmetry and reports whether P is positive semi-definite within tolerance (smallest eigenvalue).
double min_eigenvalue(const State &s);

} // namespace state_helper
} // namespace ovton::msckf
