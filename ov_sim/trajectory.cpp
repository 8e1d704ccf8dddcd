#include "ov_sim/trajectory.h"
#include "ov_core/types/errors.h"

#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>

namespace ovton::sim {

namespace {

/// Uniform cubic B-spline basis and its first two derivatives (w.r.t. u) at u in [0, 1].
struct Basis {
  double b[4], d1[4], d2[4];
  explicit Basis(double u) {
    const double u2 = u * u, u3 = u2 * u, w = 1.0 - u;
    b[0] = w * w * w / 6.0;
    b[1] = (3.0 * u3 - 6.0 * u2 + 4.0) / 6.0;
    b[2] = (-3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0) / 6.0;
    b[3] = u3 / 6.0;
    d1[0] = -w * w / 2.0;
    d1[1] = (3.0 * u2 - 4.0 * u) / 2.0;
    d1[2] = (-3.0 * u2 + 2.0 * u + 1.0) / 2.0;
    d1[3] = u2 / 2.0;
    d2[0] = w;
    d2[1] = 3.0 * u - 2.0;
    d2[2] = -3.0 * u + 1.0;
    d2[3] = u;
  }
};

/// Angular velocity in body from a unit quaternion q = (w, v) and its derivative: 2 * vec(conj(q) * dq).
Eigen::Vector3d omega_body(const Eigen::Vector4d &q, const Eigen::Vector4d &dq) {
  const double w = q(0), dw = dq(0);
  const Eigen::Vector3d v = q.tail<3>(), dv = dq.tail<3>();
  return 2.0 * (w * dv - dw * v - v.cross(dv));
}

} // namespace

SplineTrajectory::SplineTrajectory(const std::vector<ovton::core::StateSample> &gt, int64_t t_begin_ns,
                                   int64_t t_end_ns, double knot_dt_s, const std::string &source)
    : t_begin_ns_(t_begin_ns), t_end_ns_(t_end_ns), dt_(knot_dt_s), source_(source) {
  if (gt.size() < 4)
    throw ovton::core::UsageError("trajectory fit: need at least 4 ground-truth poses, got " +
                                  std::to_string(gt.size()));
  if (!(knot_dt_s > 0.0))
    throw ovton::core::UsageError("trajectory fit: knot spacing must be positive");
  if (t_end_ns <= t_begin_ns)
    throw ovton::core::UsageError("trajectory fit: empty time range");
  if (t_begin_ns < gt.front().t_ns || t_end_ns > gt.back().t_ns) {
    throw ovton::core::UsageError("trajectory fit: requested [" +
                                  std::to_string(ovton::core::ns_to_s(t_begin_ns - gt.front().t_ns)) + ", " +
                                  std::to_string(ovton::core::ns_to_s(t_end_ns - gt.front().t_ns)) +
                                  "] s (from the first pose) lies outside the ground truth, which spans " +
                                  std::to_string(ovton::core::ns_to_s(gt.back().t_ns - gt.front().t_ns)) + " s");
  }
  for (const auto &s : gt)
    if (!s.has_orientation)
      throw ovton::core::UsageError(
          "trajectory fit: ground truth must carry orientation (position-only sources cannot drive "
          "an IMU simulation)");

  // Fit a little beyond the requested span so the ends are as well constrained as the middle.
  const int64_t margin = ovton::core::s_to_ns(1.0);
  const int64_t fit_begin = std::max(gt.front().t_ns, t_begin_ns - margin);
  const int64_t fit_end = std::min(gt.back().t_ns, t_end_ns + margin);
  t0_ns_ = fit_begin;
  const int n_seg = std::max(1, static_cast<int>(std::ceil(ovton::core::ns_to_s(fit_end - fit_begin) / dt_)));
  const int n_cp = n_seg + 3;

  std::vector<Eigen::Triplet<double>> trip;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n_cp, 7);
  Eigen::Vector4d q_prev(1, 0, 0, 0);
  bool first = true;
  int used = 0;
  for (const auto &s : gt) {
    if (s.t_ns < fit_begin || s.t_ns > fit_end)
      continue;
    const double x = ovton::core::ns_to_s(s.t_ns - t0_ns_) / dt_;
    const int i = std::clamp(static_cast<int>(std::floor(x)), 0, n_seg - 1);
    const Basis B(x - i);
    Eigen::Vector4d q(s.q_WB.w(), s.q_WB.x(), s.q_WB.y(), s.q_WB.z());
    q.normalize();
    if (!first && q.dot(q_prev) < 0.0)
      q = -q; // q and -q are the same rotation; the spline needs a continuous representative
    q_prev = q;
    first = false;
    Eigen::Matrix<double, 7, 1> y;
    y << s.p, q;
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b)
        trip.emplace_back(i + a, i + b, B.b[a] * B.b[b]);
      rhs.row(i + a) += B.b[a] * y.transpose();
    }
    ++used;
  }
  if (used < 4)
    throw ovton::core::UsageError("trajectory fit: fewer than 4 poses inside the requested span");
  // Small second-difference penalty: keeps control points defined across gaps in the ground truth without
  // visibly smoothing where there is data (about 20 samples per knot at 200 Hz).
  const double lambda = 1e-3;
  for (int i = 1; i + 1 < n_cp; ++i) {
    const int idx[3] = {i - 1, i, i + 1};
    const double c[3] = {1.0, -2.0, 1.0};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        trip.emplace_back(idx[a], idx[b], lambda * c[a] * c[b]);
  }
  Eigen::SparseMatrix<double> A(n_cp, n_cp);
  A.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
  if (solver.info() != Eigen::Success)
    throw ovton::core::UsageError(
        "trajectory fit: normal equations are singular (ground truth too sparse for knot spacing)");
  const Eigen::MatrixXd cp = solver.solve(rhs);
  cp_pos_.resize(n_cp);
  cp_quat_.resize(n_cp);
  for (int i = 0; i < n_cp; ++i) {
    cp_pos_[i] = cp.block<1, 3>(i, 0).transpose();
    cp_quat_[i] = cp.block<1, 4>(i, 3).transpose();
  }
}

TrajectorySample SplineTrajectory::sample(int64_t t_ns) const {
  t_ns = std::clamp(t_ns, t_begin_ns_, t_end_ns_);
  const int n_seg = static_cast<int>(cp_pos_.size()) - 3;
  const double x = ovton::core::ns_to_s(t_ns - t0_ns_) / dt_;
  const int i = std::clamp(static_cast<int>(std::floor(x)), 0, n_seg - 1);
  const Basis B(x - i);
  TrajectorySample out;
  Eigen::Vector4d s = Eigen::Vector4d::Zero(), ds = Eigen::Vector4d::Zero();
  for (int a = 0; a < 4; ++a) {
    out.p_W += B.b[a] * cp_pos_[i + a];
    out.v_W += B.d1[a] * cp_pos_[i + a];
    out.a_W += B.d2[a] * cp_pos_[i + a];
    s += B.b[a] * cp_quat_[i + a];
    ds += B.d1[a] * cp_quat_[i + a];
  }
  out.v_W /= dt_;
  out.a_W /= dt_ * dt_;
  ds /= dt_;
  const double n = s.norm();
  const Eigen::Vector4d q = s / n;
  const Eigen::Vector4d dq = (ds - q * q.dot(ds)) / n; // derivative of s/|s|
  out.q_WB = Eigen::Quaterniond(q(0), q(1), q(2), q(3));
  out.w_B = omega_body(q, dq);
  return out;
}

LissajousTrajectory::LissajousTrajectory(double duration_s, int64_t t_begin_ns, double agility)
    : t_begin_ns_(t_begin_ns), duration_s_(duration_s), agility_(agility) {
  if (!(duration_s > 0.0))
    throw ovton::core::UsageError("builtin trajectory: duration must be positive");
  if (!(agility >= 0.0 && agility <= 3.0))
    throw ovton::core::UsageError("builtin trajectory: agility must lie in [0, 3]");
}

std::string LissajousTrajectory::describe() const {
  return agility_ > 0.0 ? "builtin:lissajous agility " + std::to_string(agility_) : "builtin:lissajous";
}

TrajectorySample LissajousTrajectory::sample(int64_t t_ns) const {
  const double t = std::clamp(ovton::core::ns_to_s(t_ns - t_begin_ns_), 0.0, duration_s_);
  TrajectorySample out;
  // Position: amplitudes keep >= 1 m to every wall of the 6 x 6 x 3 room; speeds up to ~1.4 m/s as in EuRoC.
  const Eigen::Vector3d A(2.0, 2.0, 0.6), w(0.5, 0.7, 0.9), ph(0.0, 1.1, 0.4), c(0.0, 0.0, 1.5);
  for (int k = 0; k < 3; ++k) {
    const double arg = w(k) * t + ph(k);
    out.p_W(k) = c(k) + A(k) * std::sin(arg);
    out.v_W(k) = A(k) * w(k) * std::cos(arg);
    out.a_W(k) = -A(k) * w(k) * w(k) * std::sin(arg);
  }
  // Orientation R_WB = Rz(yaw) Ry(pitch) Rx(roll) R_base; R_base turns the EuRoC body (x up, z = camera axis)
  // so the camera looks along world x before yaw.
  double yaw = 0.6 * t + 0.8 * std::sin(0.4 * t), dyaw = 0.6 + 0.32 * std::cos(0.4 * t);
  double pitch = 0.15 * std::sin(1.1 * t), dpitch = 0.165 * std::cos(1.1 * t);
  double roll = 0.2 * std::sin(0.9 * t + 0.3), droll = 0.18 * std::cos(0.9 * t + 0.3);
  if (agility_ > 0.0) { // amplitude a·A at frequency w: angular acceleration up to a·A·w²
    const double a = agility_;
    yaw += a * 0.12 * std::sin(3.7 * t + 1.0), dyaw += a * 0.12 * 3.7 * std::cos(3.7 * t + 1.0);
    pitch += a * 0.10 * std::sin(3.3 * t), dpitch += a * 0.10 * 3.3 * std::cos(3.3 * t);
    roll += a * 0.10 * std::sin(2.9 * t + 0.5), droll += a * 0.10 * 2.9 * std::cos(2.9 * t + 0.5);
  }
  const Eigen::Matrix3d Rz = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d Ry = Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Matrix3d Rx = Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()).toRotationMatrix();
  Eigen::Matrix3d R_base;
  R_base << 0, 0, 1, 0, -1, 0, 1, 0, 0;
  const Eigen::Matrix3d R = Rz * Ry * Rx * R_base;
  const Eigen::Vector3d w_W = dyaw * Eigen::Vector3d::UnitZ() + dpitch * (Rz * Eigen::Vector3d::UnitY()) +
                              droll * (Rz * Ry * Eigen::Vector3d::UnitX());
  out.q_WB = Eigen::Quaterniond(R).normalized();
  out.w_B = R.transpose() * w_W;
  return out;
}

ovton::core::StateSample to_state_sample(const TrajectorySample &s, int64_t t_ns) {
  ovton::core::StateSample o;
  o.t_ns = t_ns;
  o.p = s.p_W;
  o.q_WB = s.q_WB;
  o.v = s.v_W;
  o.has_orientation = true;
  o.has_velocity = true;
  return o;
}

} // namespace ovton::sim
