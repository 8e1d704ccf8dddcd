#include "ov_eval/diagnose/regression.h"

#include <Eigen/Dense>
#include <boost/math/distributions/fisher_f.hpp>

#include <algorithm>
#include <cmath>
#include <exception>

namespace ovton::eval::diag {

using Eigen::MatrixXd;
using Eigen::VectorXd;

double huber_rho(double e, double c) {
  const double a = std::abs(e);
  return a <= c ? 0.5 * e * e : c * a - 0.5 * c * c;
}

namespace {
/// Newey-West's weight of scores l clusters apart with `lags` lags.
double bartlett_weight(int l, int lags) {
  return 1.0 - l / (lags + 1.0);
}
} // namespace

// The scale is fixed (not re-estimated per fit) so that losses of different candidates compare. Scores are summed per
// cluster: residuals of one track share the triangulated point (rate rows of one second share tracks) and are not
// independent, so per-row standard errors would be too small.
Fit fit_huber(const MatrixXd &X, const VectorXd &r, const Design &d, double k, const std::vector<char> *mask) {
  const Eigen::Index n = r.size(), p = X.cols();
  const double c = k * d.scale;
  Fit f;
  f.beta = VectorXd::Zero(p);
  VectorXd w = VectorXd::Ones(n);
  if (mask)
    for (Eigen::Index i = 0; i < n; ++i)
      w(i) = (*mask)[i] ? 1.0 : 0.0;
  const VectorXd w_mask = w;
  if (p > 0) {
    for (int it = 0; it < 12; ++it) {
      const MatrixXd A = X.transpose() * w.asDiagonal() * X;
      const VectorXd b = X.transpose() * w.cwiseProduct(r);
      Eigen::LDLT<MatrixXd> ldlt(A + 1e-12 * A.diagonal().cwiseAbs().maxCoeff() * MatrixXd::Identity(p, p));
      const VectorXd beta_new = ldlt.solve(b);
      const bool converged = (beta_new - f.beta).norm() <= 1e-9 * (1 + beta_new.norm());
      f.beta = beta_new;
      const VectorXd e = r - X * f.beta;
      for (Eigen::Index i = 0; i < n; ++i)
        w(i) = w_mask(i) * (std::abs(e(i)) <= c ? 1.0 : c / std::abs(e(i)));
      if (converged && it > 0)
        break;
    }
  }
  f.e = r - X * f.beta;
  for (Eigen::Index i = 0; i < n; ++i)
    if (w_mask(i) > 0)
      f.loss += huber_rho(f.e(i), c);
  if (p > 0) {
    const MatrixXd A = X.transpose() * w.asDiagonal() * X;
    MatrixXd S = MatrixXd::Zero(d.n_clusters, p);
    for (Eigen::Index i = 0; i < n; ++i)
      if (w(i) > 0)
        S.row(d.cluster[i]) += (w(i) * f.e(i)) * X.row(i);
    const MatrixXd Ainv = A.ldlt().solve(MatrixXd::Identity(p, p));
    const double g = d.n_clusters > 1 ? double(d.n_clusters) / (d.n_clusters - 1) : 1.0;
    MatrixXd meat = S.transpose() * S;
    // Clusters in time order whose scores still correlate a few clusters apart: Newey-West, Bartlett weights.
    for (int l = 1; l <= d.hac_lags && l < d.n_clusters; ++l) {
      const MatrixXd C = S.bottomRows(d.n_clusters - l).transpose() * S.topRows(d.n_clusters - l);
      meat += bartlett_weight(l, d.hac_lags) * (C + C.transpose());
    }
    f.cov = g * Ainv * meat * Ainv;
  }
  f.w = w;
  return f;
}

namespace {
/// The sandwich of a fit with every row its own cluster (heteroscedasticity only), at the fit's final weights.
MatrixXd per_row_covariance(const MatrixXd &X, const Fit &f) {
  const Eigen::Index p = X.cols();
  const MatrixXd Ainv = (X.transpose() * f.w.asDiagonal() * X).ldlt().solve(MatrixXd::Identity(p, p));
  const VectorXd u2 = f.w.cwiseProduct(f.e).cwiseAbs2();
  return Ainv * (X.transpose() * u2.asDiagonal() * X) * Ainv;
}
} // namespace

Fit fit_cols(const Design &d, const std::vector<int> &cols, double k, const std::vector<char> *mask) {
  MatrixXd X(d.r.size(), cols.size());
  for (size_t j = 0; j < cols.size(); ++j)
    X.col(j) = d.D.col(cols[j]);
  Fit f = fit_huber(X, d.r, d, k, mask);
  // Pooled variance ratio (Design::pooled_cols): with short columns in the fit and the reference among its columns,
  // every column's covariance becomes the per-row one scaled per column — the pooled columns by the reference's
  // ratio, the others by their own — so the matrix stays positive semi-definite.
  const auto at = [&](int col) {
    return static_cast<Eigen::Index>(std::find(cols.begin(), cols.end(), col) - cols.begin());
  };
  const Eigen::Index p = static_cast<Eigen::Index>(cols.size());
  const bool has_short = std::any_of(d.pooled_short.begin(), d.pooled_short.end(), [&](int c) { return at(c) < p; });
  if (!has_short || d.pooled_cols.empty() || at(d.pooled_cols.front()) >= p)
    return f;
  const Eigen::Index ref = at(d.pooled_cols.front());
  const MatrixXd cov_rows = per_row_covariance(X, f);
  const auto ratio = [&](Eigen::Index j) { return cov_rows(j, j) > 0 ? f.cov(j, j) / cov_rows(j, j) : 1.0; };
  const double kappa = ratio(ref);
  VectorXd g(p);
  for (Eigen::Index j = 0; j < p; ++j) {
    const bool pooled = std::find(d.pooled_cols.begin(), d.pooled_cols.end(), cols[j]) != d.pooled_cols.end();
    g(j) = std::sqrt(std::max(0.0, pooled ? kappa : ratio(j)));
  }
  f.cov = g.asDiagonal() * cov_rows * g.asDiagonal();
  return f;
}

double chi2_sf(double x, int k) {
  if (x <= 0)
    return 1.0;
  const double h = 0.5 * x;
  if (k % 2 == 0) {
    double term = 1, sum = 1;
    for (int i = 1; i < k / 2; ++i) {
      term *= h / i;
      sum += term;
    }
    return std::exp(-h) * sum;
  }
  double sum = std::erfc(std::sqrt(h));
  double term = std::sqrt(h) * 2.0 / std::sqrt(M_PI); // h^{1/2} / Γ(3/2)
  for (int i = 1; i <= (k - 1) / 2; ++i) {
    sum += std::exp(-h) * term;
    term *= h / (i + 0.5);
  }
  return sum;
}

double f_sf(double x, int k, double df) {
  if (!(x > 0))
    return 1.0;
  try {
    return boost::math::cdf(boost::math::complement(boost::math::fisher_f(k, df), x));
  } catch (const std::exception &) { // past what the incomplete beta resolves
    return 0.0;
  }
}

double Design::wald_df() const {
  double sw2 = 0;
  for (int l = 1; l <= hac_lags; ++l)
    sw2 += std::pow(bartlett_weight(l, hac_lags), 2);
  const double g = n_clusters / (1 + 2 * sw2);
  // Beyond a thousand clusters F(k, G − 1) is χ²(k) / k; below two the covariance rests on one cluster's worth of
  // data, and F(k, 1) keeps anything from passing on it.
  return g > 1000 ? 0.0 : std::max(1.0, g - 1);
}

/// Wald statistic with k dof as the two-sided Gaussian σ of the same p-value, so that "5σ" means the same thing for
/// a one-parameter and a nine-parameter candidate, and for a covariance from 20 clusters (the rates of a 20-s log:
/// one per second) and from thousands (the residual's tracks). Against χ² alone, a clean 20-s log's accelerometer
/// bias read as a 1.2 % scale at 8.3σ (docs/diagnose.md, "Few clusters").
double wald_to_sigma(double W, int k, double df) {
  if (!(W > 0) || k <= 0)
    return 0.0;
  if (k == 1 && df <= 0)
    return std::sqrt(W);
  const double p = df > 0 ? f_sf(W / k, k, df) : chi2_sf(W, k);
  if (!(p > 1e-300))
    return std::sqrt(std::max(0.0, W - (k - 1) * std::log(W))); // far past any threshold; a monotone stand-in
  double lo = 0, hi = 40;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double wald_at_sigma(double sigma, int k, double df) {
  double lo = 0, hi = 1;
  while (wald_to_sigma(hi, k, df) < sigma && hi < 1e12)
    hi *= 2;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (wald_to_sigma(mid, k, df) < sigma ? lo : hi) = mid;
  }
  return hi;
}

double median(std::vector<double> v) {
  if (v.empty())
    return 0;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + m, v.end());
  return v[m];
}

std::vector<size_t> stepwise(const Design &d, const std::vector<StepCandidate> &cands, const StepThresholds &th,
                             std::vector<StepResult> &res) {
  res.assign(cands.size(), StepResult());
  std::vector<size_t> order;
  if (cands.empty())
    return order;
  const double k = th.huber_k;
  const double loss0 = fit_cols(d, {}, k).loss;
  // A candidate's shares are of the loss of the rows it predicts (non-zero in one of its columns): on rates, the ω
  // rows and the ψ rows are different data, and a candidate predicting one kind is not diluted by the other.
  std::vector<double> own_loss0(cands.size(), loss0), gain(cands.size(), 0.0);
  std::vector<bool> usable(cands.size(), false), taken(cands.size(), false);
  for (size_t c = 0; c < cands.size(); ++c) {
    usable[c] = cands[c].skip.empty();
    if (!usable[c]) {
      res[c].note = cands[c].skip;
      continue;
    }
    std::vector<char> mask(d.r.size(), 0);
    for (Eigen::Index i = 0; i < d.r.size(); ++i)
      for (int col : cands[c].cols)
        mask[i] = mask[i] || d.D(i, col) != 0.0;
    own_loss0[c] = std::max(1e-300, fit_cols(d, {}, k, &mask).loss);
    res[c].explained_alone = (loss0 - fit_cols(d, cands[c].cols, k).loss) / own_loss0[c];
  }
  std::vector<int> selected_cols;
  double loss_sel = loss0;
  const auto strictly_contains = [&](size_t a, size_t b) {
    if (cands[a].cols.size() <= cands[b].cols.size())
      return false;
    for (int col : cands[b].cols)
      if (std::find(cands[a].cols.begin(), cands[a].cols.end(), col) == cands[a].cols.end())
        return false;
    return true;
  };
  while (true) {
    int best = -1;
    std::vector<bool> passes(cands.size(), false);
    for (size_t c = 0; c < cands.size(); ++c) {
      if (!usable[c] || taken[c])
        continue;
      std::vector<int> joint = selected_cols, own;
      for (int col : cands[c].cols)
        if (std::find(joint.begin(), joint.end(), col) == joint.end())
          joint.push_back(col), own.push_back(col);
      StepResult &cr = res[c];
      if (own.empty()) {
        cr.explained_added = 0, cr.sigma = 0;
        cr.note = "nested in a selected candidate: adds no term";
        cr.nested = true;
        continue;
      }
      const Eigen::Index q = static_cast<Eigen::Index>(own.size());
      const double df = d.wald_df();
      cr.terms = static_cast<int>(q);
      // A cluster-robust covariance of q terms from fewer independent clusters is singular. Pooled columns take the
      // per-row covariance scaled by one ratio (Design::pooled_cols), which has no such limit.
      const bool pooled = std::all_of(own.begin(), own.end(), [&](int col) {
        return std::find(d.pooled_cols.begin(), d.pooled_cols.end(), col) != d.pooled_cols.end();
      });
      cr.testable = pooled || !(df > 0 && q > df);
      if (!cr.testable) {
        cr.sigma = 0, cr.explained_added = 0;
        cr.note = "not testable on this log: " + std::to_string(q) + " terms against about " +
                  std::to_string(static_cast<int>(std::lround(df + 1))) + " independent clusters";
        continue;
      }
      if (cr.note.rfind("not testable", 0) == 0) // testable now that selected columns took some of its terms
        cr.note.clear();
      const Fit f = fit_cols(d, joint, k);
      const VectorXd bo = f.beta.tail(q);
      const MatrixXd Co = f.cov.bottomRightCorner(q, q);
      const double W = bo.dot(Co.ldlt().solve(bo));
      cr.sigma = wald_to_sigma(W, static_cast<int>(q), df);
      gain[c] = loss_sel - f.loss;
      cr.explained_added = gain[c] / own_loss0[c];
      cr.fit = f;
      cr.joint = joint;
      cr.nested = false;
      passes[c] = cr.sigma >= th.min_sigma && cr.explained_added >= th.min_explained;
    }
    for (size_t c = 0; c < cands.size(); ++c) {
      if (!passes[c])
        continue;
      bool nests = false;
      for (size_t b = 0; b < cands.size(); ++b)
        nests = nests || (b != c && passes[b] && strictly_contains(c, b));
      if (!nests && (best < 0 || res[c].explained_added > res[best].explained_added))
        best = static_cast<int>(c);
    }
    if (best < 0)
      break;
    taken[best] = true;
    res[best].selected = true;
    loss_sel -= gain[best];
    // A selected extension (drift) supersedes the candidate it contains (constant offset): it takes that one's rank
    // and the contained one is no longer the name of the effect.
    for (size_t q = 0; q < order.size(); ++q)
      if (strictly_contains(best, order[q])) {
        res[order[q]].selected = false;
        res[order[q]].note = "contained in " + cands[best].key + " (selected)";
        res[best].explained_added += res[order[q]].explained_added;
        res[order[q]].explained_added = 0;
        order.erase(order.begin() + q);
        break;
      }
    order.push_back(best);
    for (int col : cands[best].cols)
      if (std::find(selected_cols.begin(), selected_cols.end(), col) == selected_cols.end())
        selected_cols.push_back(col);
  }
  return order;
}

BinnedCurve binned_curve(const std::vector<int> &cols, const Design &d, const Fit &fit, const std::vector<int> &joint,
                         int bins) {
  BinnedCurve cur;
  const Eigen::Index n = d.r.size();
  VectorXd own = VectorXd::Zero(n), x(n);
  for (size_t j = 0; j < joint.size(); ++j)
    if (std::find(cols.begin(), cols.end(), joint[j]) != cols.end())
      own += fit.beta(j) * d.D.col(joint[j]);
  const VectorXd y = fit.e + own; // residual with everything but this effect removed
  if (cols.size() == 1) {
    x = d.D.col(cols[0]);
    const auto it = std::find(joint.begin(), joint.end(), cols[0]) - joint.begin();
    cur.slope = fit.beta(it);
  } else {
    x = own;
    cur.slope = 1.0;
  }
  std::vector<Eigen::Index> order;
  for (Eigen::Index i = 0; i < n; ++i)
    if (x(i) != 0.0)
      order.push_back(i);
  if (order.size() < static_cast<size_t>(bins) * 10)
    return cur;
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return x(a) < x(b); });
  if (!(x(order.back()) > x(order.front())))
    return cur;
  // Robust bin means: clip at the Huber threshold so a handful of outliers do not draw the curve.
  const double clip = 3.0 * d.scale;
  for (int b = 0; b < bins; ++b) {
    const size_t lo = order.size() * b / bins, hi = order.size() * (b + 1) / bins;
    double sx = 0, sy = 0, syy = 0;
    for (size_t i = lo; i < hi; ++i) {
      const double yi =
          std::clamp(y(order[i]), -clip - std::abs(cur.slope * x(order[i])), clip + std::abs(cur.slope * x(order[i])));
      sx += x(order[i]);
      sy += yi;
      syy += yi * yi;
    }
    const double m = double(hi - lo);
    cur.x.push_back(sx / m);
    cur.mean.push_back(sy / m);
    cur.se.push_back(std::sqrt(std::max(0.0, syy / m - (sy / m) * (sy / m)) / m));
  }
  return cur;
}

} // namespace ovton::eval::diag
