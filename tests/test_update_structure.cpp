// The speed paths of the MSCKF update against their dense definitions: the projected innovation covariance built from
// the Jacobian's block structure, and the EKF update over the Jacobian's columns only.
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/state/state_helper.h"
#include "ov_msckf_ton/update/updater_msckf.h"

#include <Eigen/LU>
#include <Eigen/QR>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace ovton::msckf;

namespace {

Eigen::MatrixXd random_spd(int n, std::mt19937 &rng) {
  std::normal_distribution<double> g(0, 1);
  Eigen::MatrixXd A = Eigen::MatrixXd::NullaryExpr(n, n, [&]() { return g(rng); });
  return A * A.transpose() / n + 0.1 * Eigen::MatrixXd::Identity(n, n);
}

} // namespace

TEST(UpdateStructure, ProjectedInnovationEqualsTheDenseProduct) {
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0, 1);
  for (int nd : {0, 1, 7}) { // no t_d column; t_d; t_d + extrinsics
    const int m = 6, rows = 2 * m, nc = 6 * m + nd;
    FeatureLinearization lin;
    lin.obs.resize(m);
    lin.H_x = Eigen::MatrixXd::Zero(rows, nc);
    for (int k = 0; k < m; ++k)
      lin.H_x.block<2, 6>(2 * k, 6 * k) = Eigen::Matrix<double, 2, 6>::NullaryExpr([&]() { return g(rng); });
    for (int j = 6 * m; j < nc; ++j)
      lin.H_x.col(j) = Eigen::VectorXd::NullaryExpr(rows, [&]() { return g(rng); });
    lin.H_f = Eigen::Matrix<double, Eigen::Dynamic, 3>::NullaryExpr(rows, 3, [&]() { return g(rng); });
    const Eigen::MatrixXd P = random_spd(nc, rng);
    const double sigma2 = 0.25;

    Eigen::MatrixXd Hp = lin.H_x;
    Eigen::VectorXd r = Eigen::VectorXd::Zero(rows);
    UpdaterMSCKF::nullspace_project(lin.H_f, Hp, r);
    Eigen::MatrixXd S_ref = Hp * P * Hp.transpose();
    S_ref.diagonal().array() += sigma2;

    const Eigen::MatrixXd S = UpdaterMSCKF::projected_innovation(lin, P, sigma2);
    ASSERT_EQ(S.rows(), rows - 3);
    ASSERT_EQ(S.cols(), rows - 3);
    EXPECT_LT((S - S_ref).norm(), 1e-12 * S_ref.norm()) << nd;
  }
  // A dense column in the clone block breaks the structure the shortcut relies on: it must then differ (the test
  // can fail), which is why linearize's layout is part of the contract.
  FeatureLinearization lin;
  lin.obs.resize(3);
  lin.H_x = Eigen::MatrixXd::Ones(6, 18);
  lin.H_f = Eigen::Matrix<double, Eigen::Dynamic, 3>::NullaryExpr(6, 3, [&]() { return g(rng); });
  const Eigen::MatrixXd P = random_spd(18, rng);
  Eigen::MatrixXd Hp = lin.H_x;
  Eigen::VectorXd r = Eigen::VectorXd::Zero(6);
  UpdaterMSCKF::nullspace_project(lin.H_f, Hp, r);
  const Eigen::MatrixXd S_ref = Hp * P * Hp.transpose() + Eigen::MatrixXd::Identity(3, 3);
  EXPECT_GT((UpdaterMSCKF::projected_innovation(lin, P, 1.0) - S_ref).norm(), 1e-6 * S_ref.norm());
}

TEST(UpdateStructure, ColumnEkfUpdateEqualsTheDenseUpdate) {
  // A general Jacobian, and the square upper-triangular one the MSCKF's QR compression leaves (ekf_update then forms
  // its products with the triangle only): both against the update over the whole state and the textbook form.
  for (const bool triangular : {false, true}) {
    SCOPED_TRACE(triangular ? "upper-triangular Jacobian" : "general Jacobian");
    std::mt19937 rng(11);
    std::normal_distribution<double> g(0, 1);
    State dense(true);
    // IMU 15 + t_d 1, then three clones (18) and two landmarks (6): 40 columns.
    dense.P = random_spd(40, rng) * 1e-2;
    for (int k = 0; k < 3; ++k) {
      CloneState c;
      c.t_cam_ns = k;
      c.index = 16 + 6 * k;
      dense.clones[k] = c;
    }
    for (int k = 0; k < 2; ++k) {
      LandmarkState l;
      l.id = static_cast<size_t>(k);
      l.index = 34 + 3 * k;
      dense.landmarks[l.id] = l;
    }
    State sparse = dense;
    const std::vector<int> cols = {15, 16, 17, 18, 19, 20, 21, 28, 29, 30, 31, 32, 33, 37, 38, 39};
    const int nc = static_cast<int>(cols.size()), m = triangular ? nc : 9;
    Eigen::MatrixXd Hc = Eigen::MatrixXd::NullaryExpr(m, nc, [&]() { return g(rng); });
    if (triangular)
      Hc = Hc.triangularView<Eigen::Upper>().toDenseMatrix();
    const Eigen::VectorXd r = Eigen::VectorXd::NullaryExpr(m, [&]() { return 0.01 * g(rng); });
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m, 40);
    for (int j = 0; j < nc; ++j)
      H.col(cols[j]) = Hc.col(j);
    const Eigen::MatrixXd P0 = dense.P;
    const double chi2_dense = state_helper::ekf_update(dense, H, r, 0.01);
    const double chi2_sparse = state_helper::ekf_update(sparse, cols, Hc, r, 0.01);
    EXPECT_NEAR(chi2_sparse, chi2_dense, 1e-10 * chi2_dense);
    EXPECT_LT((sparse.P - dense.P).norm(), 1e-12 * P0.norm());
    EXPECT_EQ((sparse.P - sparse.P.transpose()).norm(), 0.0); // mirrored, exactly symmetric
    // Against the textbook form P − K S Kᵀ.
    Eigen::MatrixXd S = H * P0 * H.transpose();
    S.diagonal().array() += 0.01;
    const Eigen::MatrixXd K = P0 * H.transpose() * S.inverse();
    EXPECT_LT((sparse.P - (P0 - K * S * K.transpose())).norm(), 1e-10 * P0.norm());
    EXPECT_NEAR(sparse.td, (K * r)(15), 1e-12);
    EXPECT_LT((sparse.landmarks[1].p_W - (K * r).segment<3>(37)).norm(), 1e-12);
    EXPECT_THROW(state_helper::ekf_update(sparse, {0, 99}, Eigen::MatrixXd::Zero(1, 2), Eigen::VectorXd::Zero(1), 1.0),
                 ovton::core::UsageError);
  }
}

// Correlated track errors (update.track_correlation): the whitening turns the AR(1) covariance into the identity, and
// the projected innovation of whitened rows equals Q₂ᵀ W (H P Hᵀ + σ² C) Wᵀ Q₂ formed densely.
TEST(UpdateStructure, WhitenedTrackRowsHaveIndependentErrors) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0, 1);
  const int m = 5, rows = 2 * m, nc = 6 * m + 1;
  const double rho = 0.77, sigma2 = 0.25;
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(rows, rows);
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j)
      for (int c = 0; c < 2; ++c)
        C(2 * i + c, 2 * j + c) = std::pow(rho, std::abs(i - j));
  Eigen::MatrixXd W = Eigen::MatrixXd::Identity(rows, rows);
  UpdaterMSCKF::whiten_track_rows(W, rho);
  EXPECT_LT((W * C * W.transpose() - Eigen::MatrixXd::Identity(rows, rows)).norm(), 1e-12);
  // Independent errors stay as they are; an odd row count is refused.
  Eigen::MatrixXd I = Eigen::MatrixXd::Identity(rows, rows);
  UpdaterMSCKF::whiten_track_rows(I, 0.0);
  EXPECT_EQ(I, Eigen::MatrixXd::Identity(rows, rows));
  Eigen::MatrixXd odd(3, 2);
  EXPECT_THROW(UpdaterMSCKF::whiten_track_rows(odd, rho), ovton::core::UsageError);

  FeatureLinearization lin;
  lin.obs.resize(m);
  lin.H_x = Eigen::MatrixXd::Zero(rows, nc);
  for (int k = 0; k < m; ++k)
    lin.H_x.block<2, 6>(2 * k, 6 * k) = Eigen::Matrix<double, 2, 6>::NullaryExpr([&]() { return g(rng); });
  lin.H_x.col(6 * m) = Eigen::VectorXd::NullaryExpr(rows, [&]() { return g(rng); });
  lin.H_f = Eigen::Matrix<double, Eigen::Dynamic, 3>::NullaryExpr(rows, 3, [&]() { return g(rng); });
  const Eigen::MatrixXd P = random_spd(nc, rng);
  const Eigen::Matrix<double, Eigen::Dynamic, 3> Hf_w = W * lin.H_f;
  const Eigen::HouseholderQR<Eigen::Matrix<double, Eigen::Dynamic, 3>> qr(Hf_w);
  const Eigen::MatrixXd Q = qr.householderQ();
  const Eigen::MatrixXd Q2 = Q.rightCols(rows - 3);
  const Eigen::MatrixXd S_ref =
      Q2.transpose() * W * (lin.H_x * P * lin.H_x.transpose() + sigma2 * C) * W.transpose() * Q2;
  const Eigen::MatrixXd S = UpdaterMSCKF::projected_innovation(lin, P, sigma2, rho);
  EXPECT_LT((S - S_ref).norm(), 1e-12 * S_ref.norm());
  // Without the whitening the same rows would be taken as independent: a different S (the test can fail).
  EXPECT_GT((UpdaterMSCKF::projected_innovation(lin, P, sigma2) - S_ref).norm(), 1e-3 * S_ref.norm());
}

// A separately reported covariance (State::P_report; update.covariance_track_correlation, slam.covariance_sigma_px):
// the mean and P move as without it (the gain of P with the σ²I weight), P_report becomes the Joseph form of that
// gain under the noise σ²I + ΔR (given as G = HᵀΔRH); ekf_update's G without a reported covariance is refused.
TEST(UpdateStructure, ReportedCovarianceIsTheJosephFormOfTheFiltersGain) {
  // Fewer rows than columns (the rows' form) and a square system (the columns' form, as after the MSCKF's compression).
  for (const int m : {7, 10}) {
    SCOPED_TRACE(m);
    std::mt19937 rng(17);
    std::normal_distribution<double> g(0, 1);
    State nominal(true);
    nominal.P = random_spd(22, rng) * 1e-2; // IMU 15 + t_d 1 + one clone
    CloneState c;
    c.index = 16;
    nominal.clones[0] = c;
    State joseph = nominal;
    // A different reported covariance (its own recursion).
    joseph.P_report = random_spd(22, rng) * 2e-2;
    const Eigen::MatrixXd Pr0 = joseph.P_report;
    const std::vector<int> cols = {0, 1, 2, 15, 16, 17, 18, 19, 20, 21};
    const int nc = static_cast<int>(cols.size());
    const Eigen::MatrixXd Hc = Eigen::MatrixXd::NullaryExpr(m, nc, [&]() { return g(rng); });
    const Eigen::VectorXd r = Eigen::VectorXd::NullaryExpr(m, [&]() { return 0.01 * g(rng); });
    const Eigen::MatrixXd A = Eigen::MatrixXd::NullaryExpr(m, m, [&]() { return 0.1 * g(rng); });
    const Eigen::MatrixXd dR = A * A.transpose();
    const double sigma2 = 0.04;
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m, 22);
    for (int j = 0; j < nc; ++j)
      H.col(cols[j]) = Hc.col(j);
    const Eigen::MatrixXd P0 = nominal.P;
    const Eigen::MatrixXd G = Hc.transpose() * dR * Hc;
    EXPECT_THROW(state_helper::ekf_update(nominal, cols, Hc, r, sigma2, {nullptr, &G}), ovton::core::UsageError);
    state_helper::ekf_update(nominal, cols, Hc, r, sigma2);
    State joseph_rows = joseph;
    state_helper::ekf_update(joseph, cols, Hc, r, sigma2, {nullptr, &G});
    state_helper::ekf_update(joseph_rows, cols, Hc, r, sigma2, {&dR, nullptr}); // ΔR in the rows' basis
    Eigen::MatrixXd S = H * P0 * H.transpose();
    S.diagonal().array() += sigma2;
    const Eigen::MatrixXd K = P0 * H.transpose() * S.inverse();
    const Eigen::MatrixXd IKH = Eigen::MatrixXd::Identity(22, 22) - K * H;
    Eigen::MatrixXd R = dR;
    R.diagonal().array() += sigma2;
    const Eigen::MatrixXd Pr_ref = IKH * Pr0 * IKH.transpose() + K * R * K.transpose();
    // To double rounding times the few-fold cancellation of P_r against K H P_r.
    const double tol = 1e-12;
    EXPECT_LT((joseph.P_report - Pr_ref).norm(), tol * Pr_ref.norm());
    EXPECT_LT((joseph_rows.P_report - Pr_ref).norm(), tol * Pr_ref.norm());
    EXPECT_EQ(joseph.P_report, joseph.P_report.transpose());
    EXPECT_EQ(joseph.P, nominal.P); // the filter's own covariance, gain and mean are untouched
    EXPECT_EQ(joseph.td, nominal.td);
    EXPECT_EQ(joseph.imu.p, nominal.imu.p);
    // Without ΔR and with P_report = P the Joseph form is the filter's own P⁺ (the optimal gain's).
    State same = State(true);
    same.P = P0;
    same.clones[0] = c;
    same.start_report();
    state_helper::ekf_update(same, cols, Hc, r, sigma2);
    EXPECT_LT((same.P_report - same.P).norm(), tol * P0.norm());
    const Eigen::MatrixXd wrong = Eigen::MatrixXd::Identity(nc + 1, nc + 1);
    EXPECT_THROW(state_helper::ekf_update(joseph, cols, Hc, r, sigma2, {nullptr, &wrong}), ovton::core::UsageError);
    EXPECT_THROW(state_helper::ekf_update(joseph, cols, Hc, r, sigma2, {&wrong, nullptr}), ovton::core::UsageError);
  }
}

// The projected rows' noise factor: B Bᵀ = Q₂ᵀ C Q₂ for the AR(1) correlation C.
TEST(UpdateStructure, ProjectedTrackNoiseFactorCarriesTheArOneCorrelation) {
  std::mt19937 rng(23);
  std::normal_distribution<double> g(0, 1);
  const int m = 6, rows = 2 * m;
  const double rho = 0.8;
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(rows, rows);
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j)
      for (int c = 0; c < 2; ++c)
        C(2 * i + c, 2 * j + c) = std::pow(rho, std::abs(i - j));
  const Eigen::Matrix<double, Eigen::Dynamic, 3> H_f =
      Eigen::Matrix<double, Eigen::Dynamic, 3>::NullaryExpr(rows, 3, [&]() { return g(rng); });
  const UpdaterMSCKF::FeatureQR qr(H_f);
  const Eigen::MatrixXd Q = qr.householderQ();
  const Eigen::MatrixXd Q2 = Q.rightCols(rows - 3);
  const Eigen::MatrixXd B = UpdaterMSCKF::projected_track_noise_factor(qr, rho);
  EXPECT_LT((B * B.transpose() - Q2.transpose() * C * Q2).norm(), 1e-12 * C.norm());
  EXPECT_LT((UpdaterMSCKF::projected_track_noise_factor(qr, 0.0) - Q2.transpose()).norm(), 1e-12);
  EXPECT_THROW(UpdaterMSCKF::projected_track_noise_factor(qr, 1.0), ovton::core::UsageError);
}
