#include "ov_msckf_ton/update/triangulation.h"
#include "ov_core/types/errors.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace ovton::msckf {

std::string to_string(TriangulationQuality q) {
  switch (q) {
  case TriangulationQuality::Ok:
    return "ok";
  case TriangulationQuality::TooFewObservations:
    return "too_few_observations";
  case TriangulationQuality::LowParallax:
    return "low_parallax";
  case TriangulationQuality::IllConditioned:
    return "ill_conditioned";
  case TriangulationQuality::BadDepth:
    return "bad_depth";
  case TriangulationQuality::NotConverged:
    return "not_converged";
  case TriangulationQuality::LargeReprojection:
    return "large_reprojection";
  }
  return "unknown";
}

namespace {

/// Camera i relative to the anchor A: p_A = R_AC p_Ci + p_AC.
struct RelPose {
  Eigen::Matrix3d R_AC;
  Eigen::Vector3d p_AC;
};

/// ρ·p_Ci = R_ACᵀ ([α β 1]ᵀ − ρ p_AC) for the anchor point p_A = [α β 1]ᵀ/ρ; the projection is scale-free, so the
/// scaled point g avoids dividing by ρ and stays well defined for points far away (ρ → 0).
///   ∂g/∂α = R_ACᵀ e1,  ∂g/∂β = R_ACᵀ e2,  ∂g/∂ρ = −R_ACᵀ p_AC.
/// Returns the residual xy − π(g) and its Jacobian J = −∂π(g)/∂(α, β, ρ); false when g is behind the camera.
bool inverse_depth_residual(const RelPose &rp, const Eigen::Vector3d &abr, const Eigen::Vector2d &xy,
                            Eigen::Vector2d &res, Eigen::Matrix<double, 2, 3> *J) {
  const Eigen::Vector3d m(abr(0), abr(1), 1.0);
  const Eigen::Matrix3d R_CA = rp.R_AC.transpose();
  const Eigen::Vector3d g = R_CA * (m - abr(2) * rp.p_AC);
  if (!(g.z() > 1e-12))
    return false;
  const double iz = 1.0 / g.z();
  res = xy - Eigen::Vector2d(g.x() * iz, g.y() * iz);
  if (J) {
    Eigen::Matrix<double, 2, 3> dpi;
    dpi << iz, 0.0, -g.x() * iz * iz, 0.0, iz, -g.y() * iz * iz;
    Eigen::Matrix3d dg;
    dg.col(0) = R_CA.col(0);
    dg.col(1) = R_CA.col(1);
    dg.col(2) = -R_CA * rp.p_AC;
    *J = -dpi * dg;
  }
  return true;
}

} // namespace

TriangulationResult triangulate(const std::vector<CameraPose> &poses, const std::vector<Eigen::Vector2d> &xy,
                                size_t anchor, const TriangulationOptions &opt) {
  if (poses.size() != xy.size())
    throw ovton::core::UsageError("triangulate: " + std::to_string(poses.size()) + " poses but " +
                                  std::to_string(xy.size()) + " observations");
  TriangulationResult out;
  const size_t n = poses.size();
  if (n < 2)
    return out;
  if (anchor >= n)
    throw ovton::core::UsageError("triangulate: anchor index out of range");

  // Poses relative to the anchor; the bearings expressed in the anchor frame are rotation-compensated, so the
  // angle between them is the parallax proper.
  const CameraPose &A = poses[anchor];
  std::vector<RelPose> rel(n);
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  const Eigen::Vector3d b_anchor = Eigen::Vector3d(xy[anchor].x(), xy[anchor].y(), 1.0).normalized();
  double max_angle = 0.0;
  for (size_t i = 0; i < n; ++i) {
    rel[i].R_AC = A.R_WC.transpose() * poses[i].R_WC;
    rel[i].p_AC = A.R_WC.transpose() * (poses[i].p_WC - A.p_WC);
    const Eigen::Vector3d b = rel[i].R_AC * Eigen::Vector3d(xy[i].x(), xy[i].y(), 1.0).normalized();
    max_angle = std::max(max_angle, std::atan2(b.cross(b_anchor).norm(), b.dot(b_anchor)));
    // The point minimises Σ |(I − b bᵀ)(p − c_i)|², the sum of squared distances to the rays.
    const Eigen::Matrix3d N = Eigen::Matrix3d::Identity() - b * b.transpose();
    M += N;
    rhs += N * rel[i].p_AC;
  }
  out.parallax_rad = max_angle;
  if (max_angle < opt.min_parallax_deg * M_PI / 180.0) {
    out.quality = TriangulationQuality::LowParallax;
    return out;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(M);
  const Eigen::Vector3d ev = es.eigenvalues();
  if (!(ev(0) > 0.0) || ev(2) / ev(0) > opt.max_condition) {
    out.quality = TriangulationQuality::IllConditioned;
    return out;
  }
  const Eigen::Vector3d p_A0 = M.ldlt().solve(rhs);
  out.p_W = A.R_WC * p_A0 + A.p_WC;
  if (!(p_A0.z() > opt.min_depth) || !(p_A0.z() < opt.max_depth) || !p_A0.allFinite()) {
    out.quality = TriangulationQuality::BadDepth;
    return out;
  }

  // Levenberg-Marquardt on (α, β, ρ); the damping only matters far from the solution, where plain Gauss-Newton can
  // overshoot ρ to negative values.
  Eigen::Vector3d abr(p_A0.x() / p_A0.z(), p_A0.y() / p_A0.z(), 1.0 / p_A0.z());
  auto cost_of = [&](const Eigen::Vector3d &x, double &cost) {
    cost = 0.0;
    Eigen::Vector2d r;
    for (size_t i = 0; i < n; ++i) {
      if (!inverse_depth_residual(rel[i], x, xy[i], r, nullptr))
        return false;
      cost += r.squaredNorm();
    }
    return true;
  };
  double cost = 0.0;
  if (!cost_of(abr, cost)) {
    out.quality = TriangulationQuality::BadDepth;
    return out;
  }
  double lambda = 1e-3;
  bool converged = false;
  int it = 0;
  for (; it < opt.max_iterations && !converged; ++it) {
    Eigen::Matrix3d JtJ = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Jtr = Eigen::Vector3d::Zero();
    Eigen::Vector2d r;
    Eigen::Matrix<double, 2, 3> J;
    for (size_t i = 0; i < n; ++i) {
      inverse_depth_residual(rel[i], abr, xy[i], r, &J);
      JtJ += J.transpose() * J;
      Jtr += J.transpose() * r;
    }
    // Retry with more damping until the cost decreases; a step that does not decrease it at any damping means we
    // are at the minimum to machine precision.
    bool stepped = false;
    for (int tries = 0; tries < 10 && !stepped; ++tries) {
      Eigen::Matrix3d A_lm = JtJ;
      A_lm.diagonal() *= (1.0 + lambda);
      const Eigen::Vector3d dx = -A_lm.ldlt().solve(Jtr);
      const Eigen::Vector3d cand = abr + dx;
      double c_new = 0.0;
      if (dx.allFinite() && cost_of(cand, c_new) && c_new <= cost) {
        abr = cand;
        converged = dx.norm() < opt.step_tolerance * std::max(1.0, abr.norm()) || cost - c_new < 1e-16 * cost;
        cost = c_new;
        lambda = std::max(1e-9, lambda / 10.0);
        stepped = true;
      } else {
        lambda *= 10.0;
      }
    }
    if (!stepped)
      converged = true;
  }
  out.iterations = it;
  const Eigen::Vector3d p_A = Eigen::Vector3d(abr(0), abr(1), 1.0) / abr(2);
  out.p_W = A.R_WC * p_A + A.p_WC;
  out.reproj_rms = std::sqrt(cost / static_cast<double>(n));
  if (!converged) {
    out.quality = TriangulationQuality::NotConverged;
    return out;
  }
  for (size_t i = 0; i < n; ++i) {
    const double z = (rel[i].R_AC.transpose() * (p_A - rel[i].p_AC)).z();
    if (!(abr(2) > 0.0) || !(z > opt.min_depth) || !(z < opt.max_depth)) {
      out.quality = TriangulationQuality::BadDepth;
      return out;
    }
  }
  if (out.reproj_rms > opt.max_reproj_rms) {
    out.quality = TriangulationQuality::LargeReprojection;
    return out;
  }
  out.quality = TriangulationQuality::Ok;
  return out;
}

} // namespace ovton::msckf
