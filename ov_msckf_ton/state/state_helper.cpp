#include "ov_msckf_ton/state/state_helper.h"
#include "ov_core/types/errors.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <string>
#include <vector>

namespace ov_msckf_ton {
namespace state_helper {

void propagate_covariance(State &s, const Eigen::Matrix<double, 15, 15> &Phi, const Eigen::Matrix<double, 15, 15> &Q) {
  const int n = s.dim();
  constexpr int I = ImuState::kSize;
  const Eigen::Matrix<double, 15, 15> Pii = Phi * s.P.topLeftCorner<I, I>() * Phi.transpose() + Q;
  // Only the IMU block is recomputed; the rest of P keeps its exact symmetry (its cross terms are mirrored).
  s.P.topLeftCorner<I, I>() = 0.5 * (Pii + Pii.transpose());
  if (n > I) {
    const Eigen::MatrixXd Pix = Phi * s.P.topRightCorner(I, n - I);
    s.P.topRightCorner(I, n - I) = Pix;
    s.P.bottomLeftCorner(n - I, I) = Pix.transpose();
  }
}

void propagate_covariance(State &s, const Eigen::Matrix<double, 15, 15> &Phi, const Eigen::Matrix<double, 15, 15> &Q,
                          const Eigen::Matrix<double, 15, 12> &Gamma, int cal_index) {
  constexpr int I = ImuState::kSize;
  const Eigen::MatrixXd rows = Phi * s.P.topRows(I) + Gamma * s.P.middleRows(cal_index, 12); // A·P, 15 x n
  const Eigen::Matrix<double, 15, 15> Pii =
      rows.leftCols(I) * Phi.transpose() + rows.middleCols(cal_index, 12) * Gamma.transpose() + Q;
  s.P.topRows(I) = rows;
  s.P.leftCols(I) = rows.transpose();
  s.P.topLeftCorner<I, I>() = 0.5 * (Pii + Pii.transpose());
}

void clone(State &s, int64_t t_cam_ns, bool td_coupled, const Eigen::Vector3d &w_B, const Eigen::Vector3d &v_W) {
  if (s.clones.count(t_cam_ns))
    throw ov_core::UsageError("clone for image " + std::to_string(t_cam_ns) + " already exists");
  const int n = s.dim();
  // J maps the current error state to the clone's error [δθ_c δp_c].
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(6, n);
  J.block<3, 3>(0, ImuState::kTheta).setIdentity();
  J.block<3, 3>(3, ImuState::kPos).setIdentity();
  if (td_coupled && s.estimates_td()) {
    J.block<3, 1>(0, s.td_index) = s.imu.R * w_B; // world-frame rotation error: R(t+δ) = Exp(R ω δ) R(t)
    J.block<3, 1>(3, s.td_index) = v_W;
  }
  const Eigen::MatrixXd PJt = s.P * J.transpose();
  Eigen::MatrixXd Pn(n + 6, n + 6);
  Pn.topLeftCorner(n, n) = s.P;
  Pn.topRightCorner(n, 6) = PJt;
  Pn.bottomLeftCorner(6, n) = PJt.transpose();
  Pn.bottomRightCorner(6, 6) = J * PJt;
  s.P = 0.5 * (Pn + Pn.transpose());

  CloneState c;
  c.t_cam_ns = t_cam_ns;
  c.t_imu_ns = s.t_imu_ns;
  c.td_ref = s.td;
  c.R = s.imu.R;
  c.p = s.imu.p;
  c.has_fej = true;
  c.R_fej = c.R;
  c.p_fej = c.p;
  c.has_motion = true;
  c.motion = BodyMotion{w_B, v_W};
  c.index = n;
  s.clones[t_cam_ns] = c;
}

void marginalize_clone(State &s, int64_t t_cam_ns) {
  auto it = s.clones.find(t_cam_ns);
  if (it == s.clones.end())
    throw ov_core::UsageError("no clone for image " + std::to_string(t_cam_ns));
  const int idx = it->second.index;
  s.clones.erase(it);
  s.remove_block(idx, CloneState::kSize);
}

void marginalize_landmark(State &s, size_t id) {
  auto it = s.landmarks.find(id);
  if (it == s.landmarks.end())
    throw ov_core::UsageError("no landmark " + std::to_string(id));
  const int idx = it->second.index;
  s.landmarks.erase(it);
  s.remove_block(idx, LandmarkState::kSize);
}

namespace {

/// The update once PHᵀ (n × m) and S = H P Hᵀ + σ²I (m × m) are known. P − K S Kᵀ = P − W Wᵀ with W = PHᵀ L⁻ᵀ
/// (S = L Lᵀ): one symmetric rank-m downdate of the lower triangle, mirrored, so P stays exactly symmetric
/// without forming K or a second n × n temporary.
double apply_update(State &s, const Eigen::MatrixXd &PHt, const Eigen::MatrixXd &S, const Eigen::VectorXd &r) {
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success)
    throw ov_core::UsageError("innovation covariance is not positive definite");
  const Eigen::VectorXd Sinv_r = llt.solve(r);
  const Eigen::VectorXd dx = PHt * Sinv_r;
  Eigen::MatrixXd Wt = PHt.transpose(); // m × n, becomes L⁻¹ PHᵀᵀ = Wᵀ
  llt.matrixL().solveInPlace(Wt);
  s.P.selfadjointView<Eigen::Lower>().rankUpdate(Wt.transpose(), -1.0);
  const Eigen::Index n = s.P.rows();
  for (Eigen::Index j = 1; j < n; ++j)
    for (Eigen::Index i = 0; i < j; ++i)
      s.P(i, j) = s.P(j, i);
  s.boxplus(dx);
  return r.dot(Sinv_r);
}

} // namespace

double ekf_update(State &s, const Eigen::MatrixXd &H, const Eigen::VectorXd &r, double sigma2) {
  const Eigen::MatrixXd PHt = s.P * H.transpose();
  Eigen::MatrixXd S = H * PHt;
  S.diagonal().array() += sigma2;
  return apply_update(s, PHt, S, r);
}

double ekf_update(State &s, const std::vector<int> &cols, const Eigen::MatrixXd &Hc, const Eigen::VectorXd &r,
                  double sigma2) {
  const int n = s.dim(), nc = static_cast<int>(cols.size());
  if (Hc.cols() != nc || Hc.rows() != r.size())
    throw ov_core::UsageError("ekf_update: Jacobian, columns and residual differ in size");
  Eigen::MatrixXd Pc(n, nc);
  for (int j = 0; j < nc; ++j) {
    if (cols[j] < 0 || cols[j] >= n)
      throw ov_core::UsageError("ekf_update: column " + std::to_string(cols[j]) + " outside the state");
    Pc.col(j) = s.P.col(cols[j]);
  }
  // After the MSCKF's QR compression Hc is square and upper triangular: its products then cost half.
  // (Eigen's test with precision 0: exact zeros below the diagonal.)
  const bool upper = Hc.rows() == Hc.cols() && Hc.isUpperTriangular(0.0);
  Eigen::MatrixXd PHt(n, Hc.rows()); // n × m
  if (upper)
    PHt.noalias() = Pc * Hc.transpose().triangularView<Eigen::Lower>();
  else
    PHt.noalias() = Pc * Hc.transpose();
  Eigen::MatrixXd PHt_c(nc, Hc.rows());
  for (int j = 0; j < nc; ++j)
    PHt_c.row(j) = PHt.row(cols[j]);
  Eigen::MatrixXd S(Hc.rows(), Hc.rows());
  if (upper)
    S.noalias() = Hc.triangularView<Eigen::Upper>() * PHt_c;
  else
    S.noalias() = Hc * PHt_c;
  S.diagonal().array() += sigma2;
  return apply_update(s, PHt, S, r);
}

Eigen::MatrixXd sub_covariance(const State &s, const std::vector<int> &cols) {
  const int nc = static_cast<int>(cols.size());
  Eigen::MatrixXd P(nc, nc);
  for (int j = 0; j < nc; ++j)
    for (int i = 0; i < nc; ++i)
      P(i, j) = s.P(cols[i], cols[j]);
  return P;
}

double min_eigenvalue(const State &s) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(s.P, Eigen::EigenvaluesOnly);
  return es.eigenvalues().minCoeff();
}

} // namespace state_helper
} // namespace ov_msckf_ton
