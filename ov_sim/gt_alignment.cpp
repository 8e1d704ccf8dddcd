#include "ov_sim/gt_alignment.h"
#include "ov_core/math/so3.h"
#include "ov_core/types/errors.h"
#include "ov_sim/imu_match.h"
#include "ov_sim/trajectory.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ovton::sim {

namespace {

/// Reference poses moved into the IMU's clock, world and axes, origin not yet moved.
std::vector<ovton::core::StateSample> rotated(const std::vector<ovton::core::StateSample> &ref, const GtAlignment &a) {
  const Eigen::Matrix3d R_W1W = ovton::core::so3_exp(-Eigen::Vector3d(a.tilt.x(), a.tilt.y(), 0.0));
  // The IMU reads w_I = R w_B (R = Exp(rotation), match_imu's gyro fit): R_WI = R_WB R^T.
  const Eigen::Matrix3d R_IB = ovton::core::so3_exp(a.rotation);
  const int64_t shift_ns = ovton::core::s_to_ns(a.shift_s);
  std::vector<ovton::core::StateSample> out;
  out.reserve(ref.size());
  for (const auto &s : ref) {
    ovton::core::StateSample o;
    o.t_ns = s.t_ns - shift_ns;
    o.p = R_W1W * s.p;
    o.q_WB = Eigen::Quaterniond(R_W1W * s.q_WB.toRotationMatrix() * R_IB.transpose()).normalized();
    out.push_back(o);
  }
  return out;
}

/// The IMU's origin in the (rotated) reference body: p_gt = p_ref + R_ref·λ + c + δθ × p_ref over the poses of the
/// IMU-frame ground truth inside the reference's span (c and δθ take the two worlds' offset and small rotation).
void fit_lever(const std::vector<ovton::core::StateSample> &ref, const std::vector<ovton::core::StateSample> &gt,
               GtAlignment &a) {
  Eigen::Matrix<double, 9, 9> N = Eigen::Matrix<double, 9, 9>::Zero();
  Eigen::Matrix<double, 9, 1> rhs = Eigen::Matrix<double, 9, 1>::Zero();
  double yy = 0.0;
  size_t n = 0;
  for (const auto &g : gt) {
    const auto it = std::lower_bound(ref.begin(), ref.end(), g.t_ns,
                                     [](const ovton::core::StateSample &s, int64_t t) { return s.t_ns < t; });
    if (it == ref.begin() || it == ref.end())
      continue;
    const auto &b = *it, &f = *(it - 1);
    if (b.t_ns - f.t_ns > 50000000) // a gap in the reference: no pose to compare with
      continue;
    const double u = static_cast<double>(g.t_ns - f.t_ns) / static_cast<double>(b.t_ns - f.t_ns);
    const Eigen::Vector3d p = (1.0 - u) * f.p + u * b.p;
    const Eigen::Matrix3d R = (u < 0.5 ? f : b).q_WB.toRotationMatrix(); // <= 2.5 ms apart at 200 Hz
    Eigen::Matrix<double, 3, 9> H;
    H << R, Eigen::Matrix3d::Identity(), -ovton::core::skew(p);
    const Eigen::Vector3d y = g.p - p;
    N += H.transpose() * H;
    rhs += H.transpose() * y;
    yy += y.squaredNorm();
    ++n;
  }
  // λ and c are told apart only when the body turns; demand every direction of λ be seen.
  if (n < 100)
    return;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> es(N / static_cast<double>(n));
  if (!(es.eigenvalues()(0) > 1e-4))
    return;
  const Eigen::Matrix<double, 9, 1> x = N.ldlt().solve(rhs);
  a.lever_I = x.head<3>();
  a.lever_fitted = true;
  a.lever_samples = n;
  // Residual sum of squares at the least-squares solution, from the normal equations.
  a.lever_fit_rms_m = std::sqrt(std::max(0.0, yy - x.dot(rhs)) / static_cast<double>(n));
}

/// Zero-phase Gaussian low pass of x over the (sorted) stamps t: -3 dB at cutoff_hz. Near the ends the kernel is
/// cut and renormalised.
std::vector<Eigen::Vector3d> low_pass(const std::vector<int64_t> &t, const std::vector<Eigen::Vector3d> &x,
                                      double cutoff_hz) {
  const double sigma = std::sqrt(2.0 * std::log(2.0)) / (2.0 * M_PI * cutoff_hz) / std::sqrt(2.0); // |H| = 1/sqrt(2)
  const int64_t reach = ovton::core::s_to_ns(4.0 * sigma);
  std::vector<Eigen::Vector3d> y(x.size());
  size_t lo = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    while (t[lo] < t[i] - reach)
      ++lo;
    Eigen::Vector3d acc = Eigen::Vector3d::Zero();
    double w_sum = 0.0;
    for (size_t k = lo; k < x.size() && t[k] <= t[i] + reach; ++k) {
      const double d = ovton::core::ns_to_s(t[k] - t[i]) / sigma;
      const double w = std::exp(-0.5 * d * d);
      acc += w * x[k];
      w_sum += w;
    }
    y[i] = acc / w_sum;
  }
  return y;
}

} // namespace

std::vector<ovton::core::StateSample> blend_gt(const std::vector<ovton::core::StateSample> &base,
                                               const std::vector<ovton::core::StateSample> &fine, double blend_hz,
                                               double base_knot_dt_s) {
  if (!(blend_hz > 0.0))
    throw ovton::core::UsageError("ground-truth blend: the crossover frequency must be positive");
  if (base.size() < 4 || fine.size() < 4)
    throw ovton::core::UsageError("ground-truth blend: need at least 4 poses in each ground truth");
  const int64_t t0 = std::max(base.front().t_ns, fine.front().t_ns), t1 = std::min(base.back().t_ns, fine.back().t_ns);
  if (t1 - t0 < ovton::core::s_to_ns(2.0))
    throw ovton::core::UsageError("ground-truth blend: the two ground truths overlap by less than 2 s");
  const SplineTrajectory slow(base, t0, t1, base_knot_dt_s, "blend base");
  std::vector<int64_t> t;
  std::vector<Eigen::Matrix3d> R_base;
  std::vector<Eigen::Vector3d> p_base, d_rot, d_pos;
  for (const auto &f : fine) {
    if (f.t_ns < t0 || f.t_ns > t1)
      continue;
    const TrajectorySample b = slow.sample(f.t_ns);
    t.push_back(f.t_ns);
    R_base.push_back(b.q_WB.toRotationMatrix());
    p_base.push_back(b.p_W);
    d_rot.push_back(ovton::core::so3_log(R_base.back().transpose() * f.q_WB.toRotationMatrix())); // body frame
    d_pos.push_back(f.p - b.p_W);
  }
  if (t.size() < 4)
    throw ovton::core::UsageError(
        "ground-truth blend: the fine ground truth has fewer than 4 poses inside the other's span");
  // The difference is low-passed as a rotation vector: right for the small, slowly varying rotation between two
  // ground truths of one flight in (nearly) one world; a large one means different world frames.
  double worst = 0.0;
  for (const auto &d : d_rot)
    worst = std::max(worst, d.norm());
  if (worst > 20.0 * M_PI / 180.0)
    throw ovton::core::UsageError("ground-truth blend: the two ground truths' attitudes differ by up to " +
                                  std::to_string(worst * 180.0 / M_PI) + " deg (different world frames?)");
  const std::vector<Eigen::Vector3d> lp_rot = low_pass(t, d_rot, blend_hz), lp_pos = low_pass(t, d_pos, blend_hz);
  std::vector<ovton::core::StateSample> out(t.size());
  for (size_t i = 0; i < t.size(); ++i) {
    out[i].t_ns = t[i];
    out[i].q_WB = Eigen::Quaterniond(R_base[i] * ovton::core::so3_exp(d_rot[i] - lp_rot[i])).normalized();
    out[i].p = p_base[i] + d_pos[i] - lp_pos[i];
  }
  return out;
}

GtAlignment align_gt_to_imu(const std::vector<ovton::core::ImuData> &imu,
                            const std::vector<ovton::core::StateSample> &ref,
                            const std::vector<ovton::core::StateSample> &imu_frame_gt, double knot_dt_s) {
  ImuMatchOptions mo;
  mo.knot_dt_s = knot_dt_s;
  const ImuMatchReport m = match_imu(imu, ref, mo);
  GtAlignment a;
  a.shift_s = m.gt_shift_s;
  a.rotation = m.gt_rotation;
  a.tilt = m.gt_tilt;
  if (!imu_frame_gt.empty())
    fit_lever(rotated(ref, a), imu_frame_gt, a);
  return a;
}

std::vector<ovton::core::StateSample> apply_gt_alignment(const std::vector<ovton::core::StateSample> &ref,
                                                         const GtAlignment &a) {
  std::vector<ovton::core::StateSample> out = rotated(ref, a);
  for (auto &s : out)
    s.p += s.q_WB.toRotationMatrix() * a.lever_I;
  return out;
}

std::string describe_gt_alignment(const GtAlignment &a) {
  constexpr double deg = 180.0 / M_PI;
  char b[400];
  std::snprintf(b, sizeof(b),
                "aligned to the real IMU: time shift %.3f ms, axes rotation (%.3f, %.3f, %.3f) deg, world tilt "
                "(%.3f, %.3f) deg, lever arm ",
                a.shift_s * 1e3, a.rotation.x() * deg, a.rotation.y() * deg, a.rotation.z() * deg, a.tilt.x() * deg,
                a.tilt.y() * deg);
  std::string s = b;
  if (a.lever_fitted) {
    std::snprintf(b, sizeof(b), "(%.1f, %.1f, %.1f) mm (fit rms %.1f mm over %zu poses)", a.lever_I.x() * 1e3,
                  a.lever_I.y() * 1e3, a.lever_I.z() * 1e3, a.lever_fit_rms_m * 1e3, a.lever_samples);
    s += b;
  } else {
    s += "not fitted (no IMU-frame ground truth overlapping the reference while the body turns)";
  }
  return s;
}

} // namespace ovton::sim
