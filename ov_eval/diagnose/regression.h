#pragma once
// Robust regression for `ovton diagnose`: Huber M-estimates with cluster-robust (sandwich) covariances, Wald
// statistics as Gaussian-equivalent σ, forward stepwise selection among candidate column sets, and binned partial
// residuals for the plots. Nothing here knows what a column means: the candidate table (candidates.h) and the two
// designs (residual_design.h, rate_design.h) give the columns their meaning. Tests: tests/test_robust_regression.cpp.
#include "ov_eval/diagnose.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace ovton::eval::diag {

/// Rows to be explained (r) and the columns that may explain them (D), with the clusters the rows' errors are
/// correlated within (a quarter second of updates for the residual and for the rates, a window for the accelerometer).
struct Design {
  Eigen::MatrixXd D;        ///< n × kNumCols (candidates.h); a column a design does not fill stays zero
  Eigen::VectorXd r;        ///< the data: residual components (u and v rows interleaved) or whitened rate rows
  std::vector<int> cluster; ///< cluster index per row, in [0, n_clusters)
  std::vector<double> t_s;  ///< time of each row [s from the first used row]
  int n_clusters = 0;
  /// > 0: the clusters are consecutive in time and their scores correlate up to this many clusters apart (a smooth
  /// series such as the filter's bias): Newey-West with Bartlett weights over the cluster scores.
  int hac_lags = 0;
  double scale = 1; ///< robust σ of r (fixed, so that the losses of different candidates compare)
  /// Denominator degrees of freedom of its Wald tests. A cluster-robust covariance is an average over G clusters'
  /// scores, so it is itself uncertain: with G independent clusters the Wald statistic / k follows F(k, G − 1), not
  /// χ²(k) / k. With Newey-West weights w_l over L lags the covariance has the variance of G / (1 + 2·Σ w_l²)
  /// independent clusters' (the lag-window estimator's equivalent degrees of freedom). 0: many clusters, χ²; at
  /// least 1 otherwise.
  double wald_df() const;
  /// Columns on one regressor whose variance ratio (cluster-robust over per-row) is pooled: a column that reaches a
  /// few clusters only (pooled_short, e.g. a time bin's offset: an eighth of the log) gets its per-row covariance
  /// scaled by the ratio its first column (the whole log) shows, since its own cluster-robust variance rests on too
  /// few clusters' scores (fit_cols). Empty: none.
  std::vector<int> pooled_cols, pooled_short;
  double t_mid = 0; ///< centre of the drift term
  bool have_velocity = false, have_rate = false;
  /// The accelerometer columns' coefficients are β_j = 1 − 1/(1 + s_j) (the design against gravity, accel_design.h),
  /// not s_j (the design on the filter's bias).
  bool accel_against_gravity = false;
  /// Where each row lies, for the test of structure no candidate explains (unexplained.h); empty: not tested.
  std::vector<int> region;    ///< image region 0..8 (3 × 3 grid, row-major), −1 unknown
  std::vector<double> motion; ///< image speed [px/s]
};

struct Fit {
  Eigen::VectorXd beta;
  Eigen::MatrixXd cov; ///< cluster-robust (sandwich) covariance of beta
  Eigen::VectorXd w;   ///< the rows' final weights (Huber, 0 where masked out)
  double loss = 0;     ///< Huber loss of the rows the fit used
  Eigen::VectorXd e;   ///< final residual r − X·beta
};

double huber_rho(double e, double c);

/// Huber M-estimate of r ≈ X·β by IRLS with the fixed scale d.scale and threshold k·d.scale, and its covariance by the
/// sandwich with scores summed per cluster of d. mask (optional): rows with 0 are left out of the fit and its loss.
Fit fit_huber(const Eigen::MatrixXd &X, const Eigen::VectorXd &r, const Design &d, double k,
              const std::vector<char> *mask = nullptr);
/// fit_huber of d.r on the listed columns of d.D (no columns: the loss of the data alone).
Fit fit_cols(const Design &d, const std::vector<int> &cols, double k, const std::vector<char> *mask = nullptr);

/// Survival function of chi-square with k degrees of freedom (closed forms for integer k).
double chi2_sf(double x, int k);
/// Survival function of the F distribution with (k, df) degrees of freedom.
double f_sf(double x, int k, double df);
/// Wald statistic with k dof as the two-sided Gaussian σ of the same p-value: against χ²(k), or with df > 0 against
/// k·F(k, df) (a covariance estimated from df + 1 independent clusters; Design::wald_df).
double wald_to_sigma(double W, int k, double df = 0);
/// The Wald statistic with k dof whose Gaussian-equivalent σ (wald_to_sigma) is `sigma`: the bar a candidate of k
/// terms must reach with a covariance from df + 1 independent clusters.
double wald_at_sigma(double sigma, int k, double df = 0);
/// Upper median (the element at n/2 of the sorted values); 0 for none.
double median(std::vector<double> v);

/// One candidate of a stepwise family: the columns it adds to the model.
struct StepCandidate {
  std::string key;       ///< named in the note of a candidate it supersedes
  std::vector<int> cols; ///< columns of the design
  std::string skip;      ///< non-empty: not tested, and this is why
};

/// What the selection says of one candidate.
struct StepResult {
  double explained_alone = 0; ///< share of its rows' loss it removes on its own
  double explained_added = 0; ///< share it adds to the candidates selected before it
  double sigma = 0;           ///< Gaussian-equivalent significance of its own terms
  bool selected = false;
  std::string note;       ///< skipped, nested or superseded; empty otherwise
  Fit fit;                ///< the last fit in which it had terms of its own (its estimates come from it)
  std::vector<int> joint; ///< that fit's columns, in the order of fit.beta; empty if never fitted
  bool nested = false;    ///< the last round found no term of its own (no curve is drawn)
  int terms = 0;          ///< its own terms in that fit
  /// false: its terms outnumber the design's independent clusters (Design::wald_df), so their cluster-robust
  /// covariance cannot be estimated: not testable on this design.
  bool testable = true;
};

struct StepThresholds {
  double min_sigma = 5.0, min_explained = 0.02, huber_k = 3.0;
};

/// Forward stepwise selection among `cands` on design d; fills res[c] for each candidate and returns the selected
/// ones in selection order. Shares are of the loss of the rows a candidate predicts (non-zero in one of its columns).
/// A candidate that strictly contains a passing one (drift ⊃ constant offset) waits a round and, when selected later,
/// takes the contained one's place.
std::vector<size_t> stepwise(const Design &d, const std::vector<StepCandidate> &cands, const StepThresholds &th,
                             std::vector<StepResult> &res);

/// The partial residual of the candidate with columns `cols` (the other effects of `fit` removed), binned in `bins`
/// quantile bins of its own column (one column) or of its fitted effect (several); labels are left to the caller.
BinnedCurve binned_curve(const std::vector<int> &cols, const Design &d, const Fit &fit, const std::vector<int> &joint,
                         int bins);

} // namespace ovton::eval::diag
