// The row algebra of an MSCKF update on a feature's stacked system (UpdaterMSCKF, updater_msckf.h): the projection
// onto the left nullspace of the feature's position Jacobian, the QR compression of the stacked rows, the AR(1)
// whitening of correlated track errors, the projected innovation covariance for the χ² gate, a rig's repeated clone
// columns, and the errors-in-variables bias of t_d. Split from updater_msckf.cpp, which linearises features and runs
// the update.
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/update/updater_msckf.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdlib>

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

bool UpdaterMSCKF::seen_by_further_camera(const FeatureLinearization &lin) {
  return std::any_of(lin.obs.begin(), lin.obs.end(), [](const auto &o) { return o.cam != 0; });
}

void UpdaterMSCKF::merge_repeated_columns(std::vector<int> &cols, Eigen::MatrixXd &H) {
  if (H.cols() != static_cast<Eigen::Index>(cols.size()))
    throw ovton::core::UsageError("merge_repeated_columns: H and its columns differ in size");
  std::vector<int> distinct;
  std::vector<Eigen::Index> at(cols.size());
  for (size_t j = 0; j < cols.size(); ++j) {
    const auto it = std::find(distinct.begin(), distinct.end(), cols[j]);
    at[j] = it - distinct.begin();
    if (it == distinct.end())
      distinct.push_back(cols[j]);
  }
  if (distinct.size() == cols.size())
    return;
  // From zero, in column order: the same sums, bit for bit, as adding them into a zeroed stacked system.
  Eigen::MatrixXd merged = Eigen::MatrixXd::Zero(H.rows(), static_cast<Eigen::Index>(distinct.size()));
  for (size_t j = 0; j < cols.size(); ++j)
    merged.col(at[j]) += H.col(static_cast<Eigen::Index>(j));
  H.swap(merged);
  cols.swap(distinct);
}

Eigen::MatrixXd UpdaterMSCKF::rig_track_correlation(const FeatureLinearization &lin, double rho, double rho_cam) {
  if (!(rho >= 0 && rho < 1) || !(rho_cam >= 0 && rho_cam < 1))
    throw ovton::core::UsageError("rig_track_correlation: need 0 <= rho, rho_cam < 1");
  const Eigen::Index m = static_cast<Eigen::Index>(lin.obs.size());
  std::vector<int64_t> times;
  times.reserve(lin.obs.size());
  for (const auto &o : lin.obs)
    times.push_back(o.clone->t_cam_ns);
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  std::vector<Eigen::Index> k(lin.obs.size());
  for (size_t a = 0; a < lin.obs.size(); ++a)
    k[a] = std::lower_bound(times.begin(), times.end(), lin.obs[a].clone->t_cam_ns) - times.begin();
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(2 * m, 2 * m);
  for (Eigen::Index a = 0; a < m; ++a)
    for (Eigen::Index b = 0; b < m; ++b) {
      const double c = std::pow(rho, static_cast<double>(std::abs(k[a] - k[b]))) *
                       (lin.obs[a].cam == lin.obs[b].cam ? 1.0 : rho_cam);
      C(2 * a, 2 * b) = c;
      C(2 * a + 1, 2 * b + 1) = c;
    }
  return C;
}

Eigen::MatrixXd UpdaterMSCKF::projected_rig_track_covariance(const FeatureQR &qr, Eigen::MatrixXd C) {
  if (C.rows() != qr.rows() || C.cols() != qr.rows())
    throw ovton::core::UsageError("projected_rig_track_covariance: C and the QR differ in size");
  C.applyOnTheLeft(qr.householderQ().adjoint());
  C.applyOnTheRight(qr.householderQ());
  return C;
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

void UpdaterMSCKF::merge_repeated_columns(FeatureLinearization &lin) {
  merge_repeated_columns(lin.cols, lin.H_x);
}

double UpdaterMSCKF::td_velocity_bias(const FeatureLinearization &lin, const ovton::core::Feature &feature,
                                      const VelocityProvider &velocities, const FeatureQR &qr) {
  const int m = static_cast<int>(lin.obs.size());
  if (m == 0 || !lin.obs.front().td_column)
    return 0.0;
  // Row of each observation index of each camera's track (-1: no clone, so its noise is in no row).
  std::vector<std::vector<int>> rows_of(1 + feature.more.size());
  rows_of[0].assign(feature.obs.size(), -1);
  for (size_t c = 0; c < feature.more.size(); ++c)
    rows_of[c + 1].assign(feature.more[c].obs.size(), -1);
  for (int k = 0; k < m; ++k)
    rows_of[static_cast<size_t>(lin.obs[k].cam)][lin.obs[k].obs_index] = k;
  const VelocityProvider tracked; // the further cameras' velocities are eq. 2 (velocity_of)
  // D: row block k's t_d entry is J_k·V_k with δV_k = Σ W_j·δxy_j and xy_j's noise J_j⁻¹·n_j (n_j the pixel noise of
  // row block j, as the residual carries it), so D_kj = J_k·W_j·J_j⁻¹.
  std::vector<Eigen::Matrix2d> Jd_inv(m);
  for (int k = 0; k < m; ++k)
    Jd_inv[k] = lin.obs[k].Jd.inverse();
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(2 * m, 2 * m);
  VelocityStencil st;
  bool any = false;
  for (int k = 0; k < m; ++k) {
    const int cam = lin.obs[k].cam;
    if (cam == 0)
      velocities.stencil(feature, lin.obs[k].obs_index, st);
    else
      tracked.stencil(feature.more[static_cast<size_t>(cam - 1)], lin.obs[k].obs_index, st);
    const std::vector<int> &row_of = rows_of[static_cast<size_t>(cam)];
    for (const auto &[i, w] : st.terms) {
      const int j = i < row_of.size() ? row_of[i] : -1;
      if (j < 0)
        continue;
      D.block<2, 2>(2 * k, 2 * j) += lin.obs[k].Jd * w * Jd_inv[j];
      any = true;
    }
  }
  if (!any)
    return 0.0;
  // tr(Q₂ᵀDQ₂) = tr(D) − tr(Q₁ᵀDQ₁): Q₁ (the first three columns of H_f's Q) is thin.
  const Eigen::MatrixXd Q1 = qr.householderQ() * Eigen::MatrixXd::Identity(2 * m, 3);
  return D.trace() - (Q1.transpose() * D * Q1).trace();
}

double UpdaterMSCKF::td_bias_to_remove(const FeatureLinearization &lin, const ovton::core::Feature &feature,
                                       const VelocityProvider &velocities, const FeatureQR &qr) const {
  return opt_.td_velocity_debias != 0.0 ? opt_.td_velocity_debias * td_velocity_bias(lin, feature, velocities, qr)
                                        : 0.0;
}

double UpdaterMSCKF::remove_td_bias(State &state, double bias) {
  if (bias == 0.0)
    return 0.0;
  const Eigen::VectorXd dx = -bias * state.P.col(state.td_index);
  state.boxplus(dx);
  return dx(state.td_index);
}

} // namespace ovton::msckf
