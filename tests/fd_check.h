#pragma once
// The finite-difference Jacobian that every Jacobian and gradient test checks its analytic one against: central
// differences of a function returning a vector, at a vector or at a manifold element perturbed through the same
// retraction (⊞) as the analytic Jacobian's error (docs/architecture.md: the state's rotation error is on the world
// side, R_true = Exp(δθ)·R̂). Each test keeps its own tolerance.
#include "ov_core/math/so3.h"

#include <Eigen/Core>

namespace ovtest {

/// Central-difference Jacobian of f at x in `dim` directions: column i = (f(x ⊞ h·e_i) − f(x ⊞ −h·e_i)) / 2h, with
/// x ⊞ δ = plus(x, δ) (δ an Eigen::VectorXd of size dim). f returns an Eigen vector of any fixed size.
template <typename X, typename F, typename Plus>
Eigen::MatrixXd numeric_jacobian(const F &f, const X &x, Eigen::Index dim, const Plus &plus, double h) {
  Eigen::MatrixXd J;
  for (Eigen::Index i = 0; i < dim; ++i) {
    Eigen::VectorXd d = Eigen::VectorXd::Zero(dim);
    d(i) = h;
    const Eigen::VectorXd fp = f(plus(x, d));
    const Eigen::VectorXd fm = f(plus(x, Eigen::VectorXd(-d)));
    if (i == 0)
      J.resize(fp.size(), dim);
    J.col(i) = (fp - fm) / (2 * h);
  }
  return J;
}

/// The same at a vector, perturbed additively.
template <typename F, typename Vec> Eigen::MatrixXd numeric_jacobian(const F &f, const Vec &x, double h) {
  return numeric_jacobian(
      f, x, x.size(), [](const Vec &y, const Eigen::VectorXd &d) -> Vec { return y + d; }, h);
}

/// A rotation perturbed on the world side, R ⊞ δθ = Exp(δθ)·R: the error convention of the state (state.h).
inline Eigen::Matrix3d rotation_plus(const Eigen::Matrix3d &R, const Eigen::VectorXd &d) {
  return ovton::core::so3_exp(Eigen::Vector3d(d)) * R;
}

} // namespace ovtest
