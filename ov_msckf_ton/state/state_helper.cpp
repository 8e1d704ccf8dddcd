#include "ov_msckf_ton/state/state_helper.h"
#include "ov_core/types/errors.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <string>
#include <vector>

namespace ovton::msckf {
namespace state_helper {

void propagate_covariance(State &s, const Eigen::Matrix<double, 15, 15> &Phi, const Eigen::Matrix<double, 15, 15> &Q) {
  const int n = s.dim();
  constexpr int I = ImuState::kSize;
  s.for_each_covariance([&](auto &P) {
    using T = covariance_scalar<decltype(P)>;
    const Eigen::Matrix<T, 15, 15> Phi_t = Phi.cast<T>();
    const Eigen::Matrix<T, 15, 15> Pii = Phi_t * P.template topLeftCorner<I, I>() * Phi_t.transpose() + Q.cast<T>();
    // Only the IMU block is recomputed; the rest of P keeps its exact symmetry (its cross terms are mirrored).
    P.template topLeftCorner<I, I>() = T(0.5) * (Pii + Pii.transpose());
    if (n > I) {
      const Eigen::Matrix<T, I, Eigen::Dynamic> Pix = Phi_t * P.topRightCorner(I, n - I);
      P.topRightCorner(I, n - I) = Pix;
      P.bottomLeftCorner(n - I, I) = Pix.transpose();
    }
  });
}

void propagate_covariance(State &s, const Eigen::Matrix<double, 15, 15> &Phi, const Eigen::Matrix<double, 15, 15> &Q,
                          const Eigen::Matrix<double, 15, 12> &Gamma, int cal_index) {
  constexpr int I = ImuState::kSize;
  s.for_each_covariance([&](auto &P) {
    using T = covariance_scalar<decltype(P)>;
    const Eigen::Matrix<T, 15, 15> Phi_t = Phi.cast<T>();
    const Eigen::Matrix<T, 15, 12> Gamma_t = Gamma.cast<T>();
    // A·P, 15 x n
    const Eigen::Matrix<T, I, Eigen::Dynamic> rows = Phi_t * P.topRows(I) + Gamma_t * P.middleRows(cal_index, 12);
    const Eigen::Matrix<T, 15, 15> Pii =
        rows.leftCols(I) * Phi_t.transpose() + rows.middleCols(cal_index, 12) * Gamma_t.transpose() + Q.cast<T>();
    P.topRows(I) = rows;
    P.leftCols(I) = rows.transpose();
    P.template topLeftCorner<I, I>() = T(0.5) * (Pii + Pii.transpose());
  });
}

void clone(State &s, int64_t t_cam_ns, bool td_coupled, const Eigen::Vector3d &w_B, const Eigen::Vector3d &v_W) {
  if (s.clones.count(t_cam_ns))
    throw ovton::core::UsageError("clone for image " + std::to_string(t_cam_ns) + " already exists");
  const int n = s.dim();
  // J maps the current error state to the clone's error [δθ_c δp_c].
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(6, n);
  J.block<3, 3>(0, ImuState::kTheta).setIdentity();
  J.block<3, 3>(3, ImuState::kPos).setIdentity();
  if (td_coupled && s.estimates_td()) {
    J.block<3, 1>(0, s.td_index) = s.imu.R * w_B; // world-frame rotation error: R(t+δ) = Exp(R ω δ) R(t)
    J.block<3, 1>(3, s.td_index) = v_W;
  }
  s.for_each_covariance([&](auto &P) {
    using T = covariance_scalar<decltype(P)>;
    const Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic> J_t = J.cast<T>();
    const Eigen::Matrix<T, Eigen::Dynamic, 6> PJt = P * J_t.transpose();
    const Eigen::Matrix<T, 6, 6> JPJt = J_t * PJt;
    // P is exactly symmetric (every update mirrors its lower triangle), so only the new corner needs symmetrising.
    std::decay_t<decltype(P)> Pn(n + 6, n + 6);
    Pn.topLeftCorner(n, n) = P;
    Pn.topRightCorner(n, 6) = PJt;
    Pn.bottomLeftCorner(6, n) = PJt.transpose();
    Pn.bottomRightCorner(6, 6) = T(0.5) * (JPJt + JPJt.transpose());
    P = std::move(Pn);
  });

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
    throw ovton::core::UsageError("no clone for image " + std::to_string(t_cam_ns));
  const int idx = it->second.index;
  s.clones.erase(it);
  s.remove_block(idx, CloneState::kSize);
}

void marginalize_landmark(State &s, size_t id) {
  auto it = s.landmarks.find(id);
  if (it == s.landmarks.end())
    throw ovton::core::UsageError("no landmark " + std::to_string(id));
  const int idx = it->second.index;
  s.landmarks.erase(it);
  s.remove_block(idx, LandmarkState::kSize);
}

namespace {

/// Copies the lower triangle onto the upper: the updates write the lower one only.
template <class Mat> void mirror_lower(Mat &P) {
  const Eigen::Index n = P.rows();
  for (Eigen::Index j = 1; j < n; ++j)
    for (Eigen::Index i = 0; i < j; ++i)
      P(i, j) = P(j, i);
}

/// The reported covariance's Joseph form for the gain K of P (apply_update): P_r⁺ = P_r − K H P_r − P_r Hᵀ Kᵀ +
/// K (H P_r Hᵀ + σ²I) Kᵀ + K ΔR Kᵀ, where K ΔR Kᵀ = Z G Zᵀ with Z = P⁺_c/σ² (P⁺'s columns at cols; K = P⁺Hᵀ/σ²
/// for the σ²I weight) and G = HᵀΔRH. Both forms below write P_r + A Bᵀ + B Aᵀ on the lower triangle, mirrored.
void joseph_report(State &s, const std::vector<int> &cols, const Eigen::MatrixXd &Hc, Eigen::MatrixXd &Wt,
                   const Eigen::LLT<Eigen::MatrixXd> &llt, double sigma2, const ReportNoise &noise) {
  const Eigen::Index n = s.P.rows(), m = Hc.rows(), nc = static_cast<Eigen::Index>(cols.size());
  const double s2 = sigma2;
  Eigen::MatrixXd Pr_cols(n, nc); // P_r's columns at the compact columns
  for (Eigen::Index j = 0; j < nc; ++j)
    Pr_cols.col(j) = s.P_report.col(cols[j]);
  const auto p_plus_cols = [&] { // Z = P⁺'s columns at the compact columns / σ²
    Eigen::MatrixXd Z(n, nc);
    for (Eigen::Index j = 0; j < nc; ++j)
      Z.col(j) = (s.P.col(cols[j]) / sigma2);
    return Z;
  };
  const Eigen::MatrixXd H = Hc;
  Eigen::MatrixXd A, B;
  if (m == nc) {
    // Square (the MSCKF's compressed rows): in the columns' space, K = Z Hᵀ, J = HᵀH:
    // P_r⁺ = P_r + Z Bᵀ + B Zᵀ with B = ½ Z M − P_r,c J and M = J P_r,cc J + σ²J + G — no Kᵀ solve.
    const Eigen::MatrixXd J = H.transpose() * H;
    Eigen::MatrixXd Pcc(nc, nc);
    for (Eigen::Index j = 0; j < nc; ++j)
      for (Eigen::Index i = 0; i < nc; ++i)
        Pcc(i, j) = Pr_cols(cols[i], j);
    Eigen::MatrixXd M = J * Pcc * J + s2 * J;
    if (noise.cols)
      M += *noise.cols;
    if (noise.rows)
      M += (Hc.transpose() * *noise.rows * Hc);
    A = p_plus_cols();
    B = 0.5 * A * M - Pr_cols * J;
  } else {
    // Fewer rows than columns: in the rows' space, with K = S⁻¹PHᵀ solved and T = H P_r Hᵀ + σ²I:
    // P_r⁺ = P_r + K Bᵀ + B Kᵀ with B = ½ K T − (H P_r)ᵀ, and Z G Zᵀ on top.
    llt.matrixU().solveInPlace(Wt);                        // Kᵀ = S⁻¹ PHᵀᵀ = L⁻ᵀ Wᵀ
    const Eigen::MatrixXd HPr_t = Pr_cols * H.transpose(); // (H P_r)ᵀ, n × m
    Eigen::MatrixXd HPr_t_c(nc, m);
    for (Eigen::Index j = 0; j < nc; ++j)
      HPr_t_c.row(j) = HPr_t.row(cols[j]);
    Eigen::MatrixXd T = H * HPr_t_c;
    T.diagonal().array() += s2;
    if (noise.rows)
      T += *noise.rows;
    A = Wt.transpose();
    B = 0.5 * A * T - HPr_t;
    if (noise.cols) {
      const Eigen::MatrixXd Z = p_plus_cols();
      const Eigen::MatrixXd ZG = Z * *noise.cols;
      s.P_report.triangularView<Eigen::Lower>() += ZG * Z.transpose();
    }
  }
  s.P_report.triangularView<Eigen::Lower>() += A * B.transpose();
  s.P_report.triangularView<Eigen::Lower>() += B * A.transpose();
  mirror_lower(s.P_report);
}

/// The update once PHᵀ (n × m) and S = H P Hᵀ + σ²I (m × m) are known. P − K S Kᵀ = P − W Wᵀ with W = PHᵀ L⁻ᵀ
/// (S = L Lᵀ): one symmetric rank-m downdate of the lower triangle, mirrored, so P stays exactly symmetric
/// without forming K or a second n × n temporary. The reported covariance, where kept, takes the Joseph form of the
/// same gain K under the noise σ²I + ΔR: (I − KH)P_r(I − KH)ᵀ + K(σ²I + ΔR)Kᵀ, with G = HᵀΔRH (ekf_update).
double apply_update(State &s, const std::vector<int> &cols, const Eigen::MatrixXd &Hc, const Eigen::MatrixXd &PHt,
                    const Eigen::MatrixXd &S, const Eigen::VectorXd &r, double sigma2, const ReportNoise &noise) {
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success)
    throw ovton::core::UsageError("innovation covariance is not positive definite");
  const Eigen::VectorXd Sinv_r = llt.solve(r);
  const Eigen::VectorXd dx = PHt * Sinv_r;
  Eigen::MatrixXd Wt = PHt.transpose(); // m × n, becomes L⁻¹ PHᵀᵀ = Wᵀ
  llt.matrixL().solveInPlace(Wt);
  s.P.selfadjointView<Eigen::Lower>().rankUpdate(Wt.transpose(), -1.0);
  mirror_lower(s.P);
  if (s.separate_report())
    joseph_report(s, cols, Hc, Wt, llt, sigma2, noise);
  s.boxplus(dx);
  return r.dot(Sinv_r);
}

} // namespace

double ekf_update(State &s, const Eigen::MatrixXd &H, const Eigen::VectorXd &r, double sigma2) {
  const Eigen::MatrixXd PHt = s.P * H.transpose();
  Eigen::MatrixXd S = H * PHt;
  S.diagonal().array() += sigma2;
  std::vector<int> cols;
  if (s.separate_report())
    for (int j = 0; j < s.dim(); ++j)
      cols.push_back(j);
  return apply_update(s, cols, H, PHt, S, r, sigma2, ReportNoise{});
}

double ekf_update(State &s, const std::vector<int> &cols, const Eigen::MatrixXd &Hc, const Eigen::VectorXd &r,
                  double sigma2, const ReportNoise &noise) {
  const int n = s.dim(), nc = static_cast<int>(cols.size());
  if ((noise.cols && (noise.cols->rows() != nc || noise.cols->cols() != nc)) ||
      (noise.rows && (noise.rows->rows() != r.size() || noise.rows->cols() != r.size())))
    throw ovton::core::UsageError("ekf_update: the covariance's extra noise differs in size from the rows or columns");
  if (noise.any() && !s.separate_report())
    throw ovton::core::UsageError("ekf_update: extra noise for the covariance needs a separately reported covariance");
  if (Hc.cols() != nc || Hc.rows() != r.size())
    throw ovton::core::UsageError("ekf_update: Jacobian, columns and residual differ in size");
  Eigen::MatrixXd Pc(n, nc);
  for (int j = 0; j < nc; ++j) {
    if (cols[j] < 0 || cols[j] >= n)
      throw ovton::core::UsageError("ekf_update: column " + std::to_string(cols[j]) + " outside the state");
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
  return apply_update(s, cols, Hc, PHt, S, r, sigma2, noise);
}

Eigen::MatrixXd sub_covariance(const State &s, const std::vector<int> &cols) {
  const int nc = static_cast<int>(cols.size());
  // The columns come in runs of consecutive indices (a clone's six, a landmark's three): each column is gathered
  // run by run as contiguous segments rather than element by element (it runs once per feature and update).
  std::vector<std::pair<int, int>> runs; // (position in cols, length)
  for (int i = 0; i < nc; ++i) {
    if (i > 0 && cols[i] == cols[i - 1] + 1)
      ++runs.back().second;
    else
      runs.emplace_back(i, 1);
  }
  Eigen::MatrixXd P(nc, nc);
  for (int j = 0; j < nc; ++j)
    for (const auto &[i, len] : runs)
      P.col(j).segment(i, len) = s.P.col(cols[j]).segment(cols[i], len);
  return P;
}

double min_eigenvalue(const State &s) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(s.P, Eigen::EigenvaluesOnly);
  return es.eigenvalues().minCoeff();
}

} // namespace state_helper
} // namespace ovton::msckf
