#include "ov_msckf_ton/state/propagator.h"
#include "ov_core/math/so3.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/state/state_helper.h"

#include <algorithm>

namespace ovton::msckf {

using ovton::core::skew;
using ovton::core::so3_exp;
using ovton::core::so3_jr;

namespace {

/// The step's body, shared by the plain and the calibrated form; D == nullptr means identity (and no extra work).
void imu_step_impl(const ImuState &x, const ImuIntrinsics *D, const Eigen::Vector3d &wm, const Eigen::Vector3d &am,
                   double dt, const Eigen::Vector3d &gravity, const ImuNoise &noise, ImuState &out, Mat15 *Phi,
                   Mat15 *Q, Mat15x12 *Phi_cal, bool use_fej) {
  const Eigen::Vector3d u_w = wm - x.bg, u_a = am - x.ba;
  const Eigen::Vector3d w = D ? Eigen::Vector3d(D->D_w * u_w) : u_w, a = D ? Eigen::Vector3d(D->D_a * u_a) : u_a;
  const Eigen::Matrix3d dR = so3_exp(w * dt), dR_half = so3_exp(0.5 * w * dt);
  const Eigen::Matrix3d R_mid = x.R * dR_half;
  const Eigen::Vector3d acc_W = R_mid * a + gravity;
  out = x;
  out.R = x.R * dR;
  out.v = x.v + acc_W * dt;
  out.p = x.p + x.v * dt + 0.5 * acc_W * dt * dt;
  if (!Phi && !Q && !Phi_cal)
    return;

  // World-frame rotation error: Exp(δθ) R a ≈ R a − [R a]× δθ. The rotated specific force is written as the state
  // difference it integrates to, (R_mid a) dt = v' − v − g dt and ½ (R_mid a) dt² = p' − p − v dt − ½ g dt², so
  // that with FEJ the first estimates of v and p enter exactly where OpenVINS' FEJ puts them.
  const Eigen::Vector3d v0 = use_fej ? x.v_fej : x.v, p0 = use_fej ? x.p_fej : x.p;
  const Eigen::Vector3d dv = out.v - v0 - gravity * dt;
  const Eigen::Vector3d dp = out.p - p0 - v0 * dt - 0.5 * gravity * dt * dt;
  // Bias terms: ω − δb_g rotates by Exp(−Jr(ω dt) δb_g dt) on the right of R, i.e. −R' Jr dt δb_g on the left;
  // R_mid (a) with a = a_m − b_a − δb_a.
  const Eigen::Matrix3d Ra_x = R_mid * skew(a);
  const Eigen::Matrix3d dAcc_dbg = Ra_x * so3_jr(0.5 * w * dt) * (0.5 * dt);
  const Eigen::Matrix3d dAcc_dba = -R_mid;
  constexpr int T = ImuState::kTheta, P = ImuState::kPos, V = ImuState::kVel, G = ImuState::kBg, A = ImuState::kBa;

  Mat15 F = Mat15::Identity();
  // With the intrinsics, a bias error enters through D (δω = −D_w δb_g): its columns are the plain ones times D.
  const Eigen::Matrix3d dTh_dw = out.R * so3_jr(w * dt) * dt; // ∂δθ'/∂δω
  F.block<3, 3>(T, G) = D ? Eigen::Matrix3d(-dTh_dw * D->D_w) : Eigen::Matrix3d(-dTh_dw);
  F.block<3, 3>(V, T) = -skew(dv);
  const Eigen::Matrix3d vg = D ? Eigen::Matrix3d(dAcc_dbg * D->D_w) : dAcc_dbg;
  const Eigen::Matrix3d va = D ? Eigen::Matrix3d(dAcc_dba * D->D_a) : dAcc_dba;
  F.block<3, 3>(V, G) = vg * dt;
  F.block<3, 3>(V, A) = va * dt;
  F.block<3, 3>(P, V) = Eigen::Matrix3d::Identity() * dt;
  F.block<3, 3>(P, T) = -skew(dp);
  F.block<3, 3>(P, G) = 0.5 * vg * dt * dt;
  F.block<3, 3>(P, A) = 0.5 * va * dt * dt;
  if (Phi_cal) {
    // δD_w's entry (i, j) changes ω by e_i·u_w(j), i.e. like δω = e_i u_w(j) (= −δb_g through the plain columns);
    // likewise δD_a through a (= −δb_a).
    Phi_cal->setZero();
    for (int k = 0; k < 6; ++k) {
      const int i = kTriRow[k], j = kTriCol[k];
      Phi_cal->block<3, 1>(T, k) = dTh_dw.col(i) * u_w(j);
      Phi_cal->block<3, 1>(V, k) = -dAcc_dbg.col(i) * u_w(j) * dt;
      Phi_cal->block<3, 1>(P, k) = -0.5 * dAcc_dbg.col(i) * u_w(j) * dt * dt;
      Phi_cal->block<3, 1>(V, 6 + k) = -dAcc_dba.col(i) * u_a(j) * dt;
      Phi_cal->block<3, 1>(P, 6 + k) = -0.5 * dAcc_dba.col(i) * u_a(j) * dt * dt;
    }
  }
  if (Phi)
    *Phi = F;
  if (Q) {
    // Sample noise enters the pose and velocity exactly where the bias errors do (n_g like δb_g, n_a like δb_a),
    // but it is not a change of the bias: the bias rows of those columns (F's identity) must not carry it, or the
    // accelerometer bias wanders ~10⁴× faster than its random walk and the filter cannot take the metric scale from
    // the accelerometer (test_propagation.cpp).
    Eigen::Matrix<double, 15, 6> Gn;
    Gn.leftCols<3>() = F.block<15, 3>(0, G);
    Gn.rightCols<3>() = F.block<15, 3>(0, A);
    Gn.middleRows<6>(G).setZero();
    Eigen::Matrix<double, 6, 6> Qc = Eigen::Matrix<double, 6, 6>::Zero();
    Qc.topLeftCorner<3, 3>().diagonal().setConstant(noise.sigma_w * noise.sigma_w / dt);
    Qc.bottomRightCorner<3, 3>().diagonal().setConstant(noise.sigma_a * noise.sigma_a / dt);
    *Q = Gn * Qc * Gn.transpose();
    Q->block<3, 3>(G, G).diagonal().array() += noise.sigma_wb * noise.sigma_wb * dt;
    Q->block<3, 3>(A, A).diagonal().array() += noise.sigma_ab * noise.sigma_ab * dt;
  }
}

} // namespace

void imu_step(const ImuState &x, const Eigen::Vector3d &wm, const Eigen::Vector3d &am, double dt,
              const Eigen::Vector3d &gravity, const ImuNoise &noise, ImuState &out, Mat15 *Phi, Mat15 *Q,
              bool use_fej) {
  imu_step_impl(x, nullptr, wm, am, dt, gravity, noise, out, Phi, Q, nullptr, use_fej);
}

void imu_step_calibrated(const ImuState &x, const ImuIntrinsics &D, const Eigen::Vector3d &wm,
                         const Eigen::Vector3d &am, double dt, const Eigen::Vector3d &gravity, const ImuNoise &noise,
                         ImuState &out, Mat15 *Phi, Mat15 *Q, Mat15x12 *Phi_cal, bool use_fej) {
  imu_step_impl(x, &D, wm, am, dt, gravity, noise, out, Phi, Q, Phi_cal, use_fej);
}

Propagator::Propagator(const ImuNoise &noise, double gravity_mag) : noise_(noise), gravity_(0, 0, -gravity_mag) {}

void Propagator::feed_imu(const ovton::core::ImuData &m) {
  imu_.push(m);
  // A bounded history: 5 s is far more than any window of clones needs for interpolation.
  imu_.keep_span(5000000000LL);
}

bool Propagator::propagate(State &s, int64_t t_to_ns) {
  ImuState x = s.imu;
  Mat15 Phi_total = Mat15::Identity(), Q_total = Mat15::Zero();
  // With IMU intrinsics in the state, the step also depends on them: x' = Φ x + Γ δD, accumulated as
  // Γ_total <- Φ Γ_total + Γ (the intrinsics are constants).
  const bool cal = s.calib.imu_intrinsics_index >= 0;
  ImuIntrinsics D;
  D.D_w = s.calib.D_w;
  D.D_a = s.calib.D_a;
  Mat15x12 G_total = Mat15x12::Zero();
  Eigen::Vector3d w_last = last_w_B_;
  // FEJ: the first step starts from the state an update may have moved; its Jacobian uses the first estimates.
  // The following steps start from states no update has touched, where first and current estimates agree.
  bool first = true;
  const bool ok =
      imu_.for_each_piece(s.t_imu_ns, t_to_ns, [&](const Eigen::Vector3d &wm, const Eigen::Vector3d &am, double dt) {
        Mat15 Phi, Q;
        ImuState next;
        if (cal) {
          Mat15x12 G;
          imu_step_calibrated(x, D, wm, am, dt, gravity_, noise_, next, &Phi, &Q, &G, first && use_fej_);
          G_total = Phi * G_total + G;
          w_last = D.D_w * (wm - x.bg);
        } else {
          imu_step(x, wm, am, dt, gravity_, noise_, next, &Phi, &Q, first && use_fej_);
          w_last = wm - x.bg;
        }
        first = false;
        next.set_fej();
        Phi_total = Phi * Phi_total;
        Q_total = Phi * Q_total * Phi.transpose() + Q;
        x = next;
      });
  if (!ok)
    return false;
  if (cal)
    state_helper::propagate_covariance(s, Phi_total, Q_total, G_total, s.calib.imu_intrinsics_index);
  else
    state_helper::propagate_covariance(s, Phi_total, Q_total);
  s.imu = x; // x carries the propagated values as its first estimates (set_fej in each step)
  s.t_imu_ns = t_to_ns;
  last_w_B_ = w_last;
  return true;
}

bool Propagator::predict_mean(const State &s, int64_t t_to_ns, ImuState &out) const {
  ImuState x = s.imu;
  ImuIntrinsics D;
  D.D_w = s.calib.D_w;
  D.D_a = s.calib.D_a;
  const bool cal = s.calib.imu_intrinsics_index >= 0;
  const bool ok =
      imu_.for_each_piece(s.t_imu_ns, t_to_ns, [&](const Eigen::Vector3d &wm, const Eigen::Vector3d &am, double dt) {
        ImuState next;
        if (cal)
          imu_step_calibrated(x, D, wm, am, dt, gravity_, noise_, next, nullptr, nullptr, nullptr);
        else
          imu_step(x, wm, am, dt, gravity_, noise_, next, nullptr, nullptr);
        x = next;
      });
  if (ok)
    out = x;
  return ok;
}

} // namespace ovton::msckf
