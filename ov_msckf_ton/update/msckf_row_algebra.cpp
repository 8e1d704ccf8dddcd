// The row algebra of an MSCKF update on a feature's stacked system (UpdaterMSCKF, updater_msckf.h): the projection
// onto the left nullspace of the feature's position Jacobian, the QR compression of the stacked rows, the AR(1)
// whitening of correlated track errors, and the projected innovation covariance for the χ² gate. Split from
// updater_msckf.cpp, which linearises features and runs the update.
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/update/updater_msckf.h"

#include <Eigen/QR>
#include <cmath>

namespace ovton::msckf {

void UpdaterMSCKF::nullspace_project(const Eigen::Matrix<double, Eigen::Dynamic, 3> &H_f, Eigen::MatrixXd &H_x,
                                     Eigen::VectorXd &r) {
  nullspace_project(FeatureQR(H_f), H_x, r);
}

void UpdaterMSCKF::nullspace_project(const FeatureQR &qr, Eigen::MatrixXd &H_x, Eigen::VectorXd &r) {
  const Eigen::Index rows = qr.rows();
  if (rows <= 3 || H_x.rows() != rows || r.size() != rows)
    throw ovton::core::UsageError("nullspace_project: need matching blocks with more than 3 rows");
  // Qᵀ applied by its Householder reflectors, never forming the 2m × 2m Q.
  H_x.applyOnTheLeft(qr.householderQ().adjoint());
  r.applyOnTheLeft(qr.householderQ().adjoint());
  H_x = H_x.bottomRows(rows - 3).eval();
  r = r.tail(rows - 3).eval();
}

void UpdaterMSCKF::compress(Eigen::MatrixXd &H, Eigen::VectorXd &r) {
  const Eigen::Index rows = H.rows(), cols = H.cols();
  if (rows <= cols)
    return;
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(H);
  r.applyOnTheLeft(qr.householderQ().adjoint());
  H = qr.matrixQR().topRows(cols).triangularView<Eigen::Upper>();
  r = r.head(cols).eval();
}

Eigen::MatrixXd UpdaterMSCKF::track_noise_factor(Eigen::Index rows, double rho) {
  if (rows % 2 != 0 || !(rho >= 0 && rho < 1))
    throw ovton::core::UsageError("track_noise_factor: need an even row count and 0 <= rho < 1");
  // e_k = ρ e_{k−1} + √(1 − ρ²) w_k, e_0 = w_0 (unit stationary variance): L_kj = ρ^(k−j), times √(1 − ρ²) for j > 0.
  const Eigen::Index m = rows / 2;
  const double s = std::sqrt(1.0 - rho * rho);
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(rows, rows);
  for (Eigen::Index j = 0; j < m; ++j) {
    double v = j == 0 ? 1.0 : s;
    for (Eigen::Index k = j; k < m; ++k, v *= rho) {
      L(2 * k, 2 * j) = v;
      L(2 * k + 1, 2 * j + 1) = v;
    }
  }
  return L;
}

Eigen::MatrixXd UpdaterMSCKF::projected_track_noise_factor(const FeatureQR &qr, double rho) {
  const Eigen::Index rows = qr.rows();
  if (rows <= 3)
    throw ovton::core::UsageError("projected_track_noise_factor: need more than 3 rows");
  Eigen::MatrixXd L = track_noise_factor(rows, rho);
  L.applyOnTheLeft(qr.householderQ().adjoint());
  return L.bottomRows(rows - 3);
}

void UpdaterMSCKF::whiten_track_rows(Eigen::Ref<Eigen::MatrixXd> M, double rho) {
  if (rho == 0.0)
    return;
  if (M.rows() % 2 != 0 || !(rho > -1 && rho < 1))
    throw ovton::core::UsageError("whiten_track_rows: need an even row count and |rho| < 1");
  const double s = 1.0 / std::sqrt(1.0 - rho * rho);
  // From the last observation back, so that each row is combined with its predecessor's original values.
  for (Eigen::Index k = M.rows() / 2 - 1; k >= 1; --k)
    M.middleRows<2>(2 * k) = (M.middleRows<2>(2 * k) - rho * M.middleRows<2>(2 * k - 2)) * s;
}

Eigen::MatrixXd UpdaterMSCKF::projected_innovation(const FeatureLinearization &lin, const Eigen::MatrixXd &P_sub,
                                                   double sigma2, double rho) {
  if (rho == 0.0)
    return projected_innovation(lin, FeatureQR(lin.H_f), P_sub, sigma2, rho);
  Eigen::Matrix<double, Eigen::Dynamic, 3> H_f_white = lin.H_f;
  whiten_track_rows(H_f_white, rho);
  return projected_innovation(lin, FeatureQR(H_f_white), P_sub, sigma2, rho);
}

Eigen::MatrixXd UpdaterMSCKF::projected_innovation(const FeatureLinearization &lin, const FeatureQR &qr,
                                                   const Eigen::MatrixXd &P_sub, double sigma2, double rho) {
  const int m = static_cast<int>(lin.obs.size()), rows = 2 * m, nc = static_cast<int>(lin.H_x.cols());
  const int nd = nc - 6 * m; // t_d and calibration columns, dense
  if (m < 2 || nd < 0 || lin.H_x.rows() != rows || P_sub.rows() != nc || qr.rows() != rows)
    throw ovton::core::UsageError("projected_innovation: linearisation and covariance differ in size");
  // T = H_x P, block row by block row.
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(rows, nc);
  for (int k = 0; k < m; ++k)
    T.middleRows<2>(2 * k).noalias() = lin.H_x.block<2, 6>(2 * k, 6 * k) * P_sub.middleRows<6>(6 * k);
  if (nd > 0)
    T.noalias() += lin.H_x.rightCols(nd) * P_sub.bottomRows(nd);
  // S_full = T H_xᵀ, block column by block column.
  Eigen::MatrixXd S(rows, rows);
  for (int k = 0; k < m; ++k)
    S.middleCols<2>(2 * k).noalias() = T.middleCols<6>(6 * k) * lin.H_x.block<2, 6>(2 * k, 6 * k).transpose();
  if (nd > 0)
    S.noalias() += T.rightCols(nd) * lin.H_x.rightCols(nd).transpose();
  // Correlated track errors: W S Wᵀ (qr is then of the whitened H_f), so that the noise below is σ²I again.
  if (rho != 0.0) {
    whiten_track_rows(S, rho);
    S.transposeInPlace();
    whiten_track_rows(S, rho);
  }
  S.applyOnTheLeft(qr.householderQ().adjoint());
  S.applyOnTheRight(qr.householderQ());
  Eigen::MatrixXd S2 = S.bottomRightCorner(rows - 3, rows - 3);
  S2.diagonal().array() += sigma2;
  return S2;
}

} // namespace ovton::msckf
