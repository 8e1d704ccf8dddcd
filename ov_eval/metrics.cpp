#include "ov_eval/metrics.h"

#include "ov_core/types/errors.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace ovton::eval {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kRadToDeg = 180.0 / M_PI;

std::string span_str(const std::vector<ovton::core::StateSample> &v) {
  std::ostringstream os;
  os.precision(15);
  os << "[" << ovton::core::ns_to_s(v.front().t_ns) << ", " << ovton::core::ns_to_s(v.back().t_ns) << "] s";
  return os.str();
}

/// Rotation angle of q in [0, pi]; atan2 keeps precision for small angles where acos(w) would not.
double angle_of(const Eigen::Quaterniond &q) {
  return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w()));
}

double angle_of(const Eigen::Matrix3d &R) {
  return angle_of(Eigen::Quaterniond(R));
}

ovton::core::StateSample interpolate(const ovton::core::StateSample &a, const ovton::core::StateSample &b,
                                     int64_t t_ns) {
  // Differences in int64 first: absolute stamps (~1.4e18 ns) do not fit a double's mantissa.
  const double alpha = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  ovton::core::StateSample s;
  s.t_ns = t_ns;
  s.p = (1.0 - alpha) * a.p + alpha * b.p;
  s.has_orientation = a.has_orientation && b.has_orientation;
  if (s.has_orientation)
    s.q_WB = a.q_WB.normalized().slerp(alpha, b.q_WB.normalized()); // Eigen's slerp takes the short arc
  s.has_velocity = a.has_velocity && b.has_velocity;
  if (s.has_velocity)
    s.v = (1.0 - alpha) * a.v + alpha * b.v;
  s.bg = (1.0 - alpha) * a.bg + alpha * b.bg;
  s.ba = (1.0 - alpha) * a.ba + alpha * b.ba;
  s.has_td = a.has_td && b.has_td;
  if (s.has_td)
    s.td_s = (1.0 - alpha) * a.td_s + alpha * b.td_s;
  return s;
}

double rmse(double sum_sq, int n) {
  return n > 0 ? std::sqrt(sum_sq / n) : kNaN;
}

/// Velocity of estimate row k: its own if it has one, else a finite difference of the estimated positions
/// (central inside, one-sided at the ends).
Eigen::Vector3d est_velocity(const std::vector<ovton::core::StateSample> &est, size_t k) {
  if (est[k].has_velocity)
    return est[k].v;
  if (est.size() < 2)
    return Eigen::Vector3d::Zero();
  const size_t i0 = k == 0 ? 0 : k - 1;
  const size_t i1 = k + 1 < est.size() ? k + 1 : k;
  return (est[i1].p - est[i0].p) / ovton::core::ns_to_s(est[i1].t_ns - est[i0].t_ns);
}

} // namespace

AlignMode parse_align_mode(const std::string &s) {
  if (s == "none")
    return AlignMode::None;
  if (s == "posyaw")
    return AlignMode::PosYaw;
  if (s == "se3")
    return AlignMode::SE3;
  if (s == "sim3")
    return AlignMode::Sim3;
  throw ovton::core::UsageError("unknown alignment '" + s + "' (expected posyaw, se3, sim3 or none)");
}

const char *to_string(AlignMode m) {
  switch (m) {
  case AlignMode::None:
    return "none";
  case AlignMode::PosYaw:
    return "posyaw";
  case AlignMode::SE3:
    return "se3";
  case AlignMode::Sim3:
    return "sim3";
  }
  return "?";
}

Association associate(const std::vector<ovton::core::StateSample> &est, const std::vector<ovton::core::StateSample> &gt,
                      double max_gap_s) {
  if (est.empty())
    throw ovton::core::UsageError("associate: the estimated trajectory is empty");
  if (gt.empty())
    throw ovton::core::UsageError("associate: the ground-truth trajectory is empty");
  for (size_t i = 1; i < gt.size(); ++i)
    if (gt[i].t_ns <= gt[i - 1].t_ns)
      throw ovton::core::UsageError("associate: ground-truth stamps must be strictly increasing (sample " +
                                    std::to_string(i) + " is not after sample " + std::to_string(i - 1) + ")");
  const int64_t max_gap_ns = ovton::core::s_to_ns(max_gap_s);

  Association a;
  a.est.reserve(est.size());
  a.gt.reserve(est.size());
  for (const ovton::core::StateSample &e : est) {
    if (e.t_ns < gt.front().t_ns || e.t_ns > gt.back().t_ns)
      continue;
    auto it = std::lower_bound(gt.begin(), gt.end(), e.t_ns,
                               [](const ovton::core::StateSample &s, int64_t t) { return s.t_ns < t; });
    if (it->t_ns == e.t_ns) {
      a.est.push_back(e);
      a.gt.push_back(*it);
      continue;
    }
    const ovton::core::StateSample &b = *it;
    const ovton::core::StateSample &prev = *(it - 1); // exists: e.t_ns > gt.front().t_ns here
    if (b.t_ns - prev.t_ns > max_gap_ns)
      continue;
    a.est.push_back(e);
    a.gt.push_back(interpolate(prev, b, e.t_ns));
  }
  if (a.est.empty())
    throw ovton::core::UsageError("associate: no estimate stamp falls inside the ground truth (estimate spans " +
                                  span_str(est) + ", ground truth spans " + span_str(gt) + ", max gap " +
                                  std::to_string(max_gap_s) + " s); are both in the same clock and in nanoseconds?");
  return a;
}

/// Mean squared horizontal distance from the centroid [m²] below which positions cannot fix yaw (10 cm RMS).
constexpr double kMinYawSpreadM2 = 0.01;

Alignment align(const Association &a, AlignMode mode) {
  if (a.est.empty() || a.est.size() != a.gt.size())
    throw ovton::core::UsageError("align: empty or inconsistent association");
  Alignment out;
  if (mode == AlignMode::None)
    return out;

  const size_t n = a.est.size();
  Eigen::Vector3d mu_e = Eigen::Vector3d::Zero(), mu_g = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    mu_e += a.est[i].p;
    mu_g += a.gt[i].p;
  }
  mu_e /= static_cast<double>(n);
  mu_g /= static_cast<double>(n);

  if (mode == AlignMode::SE3 || mode == AlignMode::Sim3) {
    // Umeyama 1991: maximise tr(R^T Sigma) with Sigma = sum g_c e_c^T; with scale, s = tr(D S) / sum |e_c|^2.
    Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();
    double var_e = 0.0;
    for (size_t i = 0; i < n; ++i) {
      sigma += (a.gt[i].p - mu_g) * (a.est[i].p - mu_e).transpose();
      var_e += (a.est[i].p - mu_e).squaredNorm();
    }
    // A single point (or all identical) leaves the rotation free; keep identity rather than an SVD artefact.
    if (sigma.norm() > 1e-300) {
      Eigen::JacobiSVD<Eigen::Matrix3d> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
      if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0)
        S(2, 2) = -1.0; // the best proper rotation, not a reflection
      out.R = svd.matrixU() * S * svd.matrixV().transpose();
      if (mode == AlignMode::Sim3 && var_e > 1e-300)
        out.s = (svd.singularValues().asDiagonal() * S).trace() / var_e;
    }
  } else {
    // Maximise sum g_c . Rz(theta) e_c = A cos(theta) + B sin(theta)  =>  theta = atan2(B, A).
    double A = 0.0, B = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d e = a.est[i].p - mu_e, g = a.gt[i].p - mu_g;
      A += e.x() * g.x() + e.y() * g.y();
      B += e.x() * g.y() - e.y() * g.x();
    }
    double theta = (A == 0.0 && B == 0.0) ? 0.0 : std::atan2(B, A);
    // A trajectory that barely moves horizontally (a still start) says nothing about yaw through its positions;
    // then take the mean yaw of R_gt R_estᵀ from the orientations, when both sides have them.
    double spread = 0.0;
    bool have_orientation = true;
    for (size_t i = 0; i < n; ++i) {
      spread += (a.est[i].p - mu_e).head<2>().squaredNorm();
      have_orientation = have_orientation && a.est[i].has_orientation && a.gt[i].has_orientation;
    }
    if (have_orientation && spread / static_cast<double>(n) < kMinYawSpreadM2) {
      double sy = 0.0, cy = 0.0;
      for (size_t i = 0; i < n; ++i) {
        const Eigen::Matrix3d D = a.gt[i].q_WB.toRotationMatrix() * a.est[i].q_WB.toRotationMatrix().transpose();
        const double yaw = std::atan2(D(1, 0), D(0, 0));
        sy += std::sin(yaw);
        cy += std::cos(yaw);
      }
      theta = std::atan2(sy, cy);
    }
    out.R = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  }
  out.t = mu_g - out.s * (out.R * mu_e);
  return out;
}

EvalResult evaluate(const std::vector<ovton::core::StateSample> &est, const std::vector<ovton::core::StateSample> &gt,
                    const std::vector<ovton::core::TdSample> &td_truth, const EvalOptions &opt) {
  for (size_t i = 1; i < est.size(); ++i)
    if (est[i].t_ns <= est[i - 1].t_ns)
      throw ovton::core::UsageError("evaluate: estimate stamps must be strictly increasing (row " + std::to_string(i) +
                                    " is not after row " + std::to_string(i - 1) + ")");
  for (size_t i = 1; i < td_truth.size(); ++i)
    if (td_truth[i].t_cam_ns <= td_truth[i - 1].t_cam_ns)
      throw ovton::core::UsageError("evaluate: time-offset truth stamps must be strictly increasing (sample " +
                                    std::to_string(i) + ")");

  EvalResult r;
  r.n_est = static_cast<int>(est.size());
  r.align_mode = opt.align;
  const Association a = associate(est, gt, opt.max_gap_s);
  const size_t n = a.est.size();
  r.n_matched = static_cast<int>(n);
  r.alignment = align(a, opt.align);
  const Eigen::Matrix3d &R_al = r.alignment.R;
  const Eigen::Quaterniond q_al(R_al);

  // APE and ARE.
  bool full_pose = true;
  double ape_sq = 0.0, ape_sum = 0.0, are_sq = 0.0;
  r.ape_per_pose_m.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const double e = (r.alignment.apply(a.est[i].p) - a.gt[i].p).norm();
    r.ape_per_pose_m[i] = e;
    ape_sq += e * e;
    ape_sum += e;
    r.ape_max_m = std::max(r.ape_max_m, e);
    full_pose = full_pose && a.est[i].has_orientation && a.gt[i].has_orientation;
    if (full_pose) {
      const double ang = angle_of(a.gt[i].q_WB.normalized().conjugate() * (q_al * a.est[i].q_WB.normalized()));
      are_sq += ang * ang;
    }
  }
  r.ape_rmse_m = std::sqrt(ape_sq / n);
  r.ape_mean_m = ape_sum / n;
  r.are_rmse_deg = full_pose ? std::sqrt(are_sq / n) * kRadToDeg : kNaN;

  // RPE over segments measured along the ground-truth path.
  std::vector<double> dist(n, 0.0);
  for (size_t i = 1; i < n; ++i)
    dist[i] = dist[i - 1] + (a.gt[i].p - a.gt[i - 1].p).norm();
  for (double seg : opt.rpe_segments_m) {
    RpeResult rr;
    rr.segment_m = seg;
    double t_sq = 0.0, r_sq = 0.0;
    size_t j = 0;
    for (size_t i = 0; i < n; ++i) {
      j = std::max(j, i + 1);
      while (j < n && dist[j] - dist[i] < seg)
        ++j;
      if (j >= n)
        break; // dist is non-decreasing: no later start can complete this segment either
      const ovton::core::StateSample &gi = a.gt[i], &gj = a.gt[j], &ei = a.est[i], &ej = a.est[j];
      if (full_pose) {
        // E = (T_gi^-1 T_gj)^-1 (T_ei^-1 T_ej): invariant to any rigid alignment of the estimate.
        const Eigen::Matrix3d Rgi = gi.q_WB.normalized().toRotationMatrix();
        const Eigen::Matrix3d Rei = ei.q_WB.normalized().toRotationMatrix();
        const Eigen::Matrix3d Rg_rel = Rgi.transpose() * gj.q_WB.normalized().toRotationMatrix();
        const Eigen::Matrix3d Re_rel = Rei.transpose() * ej.q_WB.normalized().toRotationMatrix();
        const Eigen::Vector3d tg_rel = Rgi.transpose() * (gj.p - gi.p);
        const Eigen::Vector3d te_rel = Rei.transpose() * (ej.p - ei.p);
        const double dt = (te_rel - tg_rel).norm();
        const double dr = angle_of(Rg_rel.transpose() * Re_rel);
        t_sq += dt * dt;
        r_sq += dr * dr;
      } else {
        // Without truth orientation there is no body frame: compare world displacements after alignment.
        const double dt = (r.alignment.s * (R_al * (ej.p - ei.p)) - (gj.p - gi.p)).norm();
        t_sq += dt * dt;
      }
      ++rr.count;
    }
    rr.trans_rmse_m = rmse(t_sq, rr.count);
    rr.rot_rmse_deg = full_pose ? rmse(r_sq, rr.count) * kRadToDeg : kNaN;
    r.rpe.push_back(rr);
  }

  // TPE (paper eq. 16) and CIT (eq. 15) over the estimate rows that carry a time offset.
  std::vector<size_t> td_rows;
  for (size_t k = 0; k < est.size(); ++k)
    if (est[k].has_td)
      td_rows.push_back(k);
  if (td_rows.empty())
    return r;

  if (!td_truth.empty()) {
    r.has_tpe = true;
    double sq = 0.0, td_sq = 0.0, td_sq_late = 0.0, nees = 0.0;
    int nees_count = 0;
    const size_t half = td_rows.size() / 2;
    for (size_t m = 0; m < td_rows.size(); ++m) {
      const size_t k = td_rows[m];
      const double td_gt = td_truth_at(td_truth, est[k].t_ns - ovton::core::s_to_ns(est[k].td_s));
      const double e = est[k].td_s - td_gt;
      const double tpe_m = e * est_velocity(est, k).norm();
      sq += tpe_m * tpe_m;
      td_sq += e * e;
      if (m >= half)
        td_sq_late += e * e;
      if (est[k].td_sigma_s > 0) {
        nees += e * e / (est[k].td_sigma_s * est[k].td_sigma_s);
        ++nees_count;
      }
    }
    r.tpe_count = static_cast<int>(td_rows.size());
    r.tpe_rmse_mm = std::sqrt(sq / td_rows.size()) * 1e3;
    r.td_err_rmse_ms = std::sqrt(td_sq / td_rows.size()) * 1e3;
    r.td_err_rmse_late_ms = std::sqrt(td_sq_late / (td_rows.size() - half)) * 1e3;
    r.td_nees = nees_count > 0 ? nees / nees_count : std::numeric_limits<double>::quiet_NaN();
  }

  const bool truth_target = opt.cit.target_from_truth;
  if (!truth_target || !td_truth.empty()) {
    r.has_cit = true;
    for (size_t m = 1; m < td_rows.size(); ++m) {
      const ovton::core::StateSample &s = est[td_rows[m]];
      const double target =
          truth_target ? td_truth_at(td_truth, s.t_ns - ovton::core::s_to_ns(s.td_s)) : opt.cit.target_s;
      if (std::abs(s.td_s - target) <= opt.cit.eps1_s &&
          std::abs(s.td_s - est[td_rows[m - 1]].td_s) <= opt.cit.eps2_s) {
        r.cit = static_cast<int>(m);
        break;
      }
    }
  }
  return r;
}

double td_truth_at(const std::vector<ovton::core::TdSample> &td, int64_t t_cam_ns) {
  if (t_cam_ns <= td.front().t_cam_ns)
    return td.front().td_s;
  if (t_cam_ns >= td.back().t_cam_ns)
    return td.back().td_s;
  auto it = std::upper_bound(td.begin(), td.end(), t_cam_ns,
                             [](int64_t t, const ovton::core::TdSample &s) { return t < s.t_cam_ns; });
  const ovton::core::TdSample &b = *it;
  const ovton::core::TdSample &a = *(it - 1);
  const double alpha = static_cast<double>(t_cam_ns - a.t_cam_ns) / static_cast<double>(b.t_cam_ns - a.t_cam_ns);
  return (1.0 - alpha) * a.td_s + alpha * b.td_s;
}

} // namespace ovton::eval
