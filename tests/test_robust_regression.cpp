// The robust regression behind `ovton diagnose` (ov_eval/diagnose/regression.h) on its own, without a residual log:
// Huber estimates resist outliers, cluster-robust standard errors match the spread they claim, Wald statistics map to
// the right σ, and the stepwise selection picks planted columns, lets an extension supersede what it contains and
// reports nested and skipped candidates.
#include "ov_eval/diagnose/regression.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace ovton::eval::diag;

namespace {

/// A design of `cols` standard-normal columns over n_clusters clusters of `per_cluster` rows each; r left zero.
Design random_design(int n_clusters, int per_cluster, int cols, std::mt19937 &rng) {
  std::normal_distribution<double> N;
  Design d;
  const int n = n_clusters * per_cluster;
  d.D.resize(n, cols);
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < cols; ++c)
      d.D(i, c) = N(rng);
  d.r = Eigen::VectorXd::Zero(n);
  d.n_clusters = n_clusters;
  for (int i = 0; i < n; ++i)
    d.cluster.push_back(i / per_cluster);
  return d;
}

/// The robust scale the designs use: 1.4826·MAD of the data.
double robust_scale(const Eigen::VectorXd &r) {
  std::vector<double> a(r.size());
  for (Eigen::Index i = 0; i < r.size(); ++i)
    a[i] = std::abs(r(i));
  return 1.4826 * median(a);
}

/// Plants r = D·beta (beta over the first columns) plus Gaussian noise of σ `noise`, and sets the robust scale.
void plant(Design &d, const std::vector<double> &beta, double noise, std::mt19937 &rng) {
  std::normal_distribution<double> N;
  for (Eigen::Index i = 0; i < d.r.size(); ++i) {
    d.r(i) = 0.0;
    for (size_t c = 0; c < beta.size(); ++c)
      d.r(i) += beta[c] * d.D(i, static_cast<Eigen::Index>(c));
    d.r(i) += noise * N(rng);
  }
  d.scale = robust_scale(d.r);
}

} // namespace

TEST(RobustRegression, MedianIsTheUpperMiddleElement) {
  EXPECT_EQ(median({}), 0.0);
  EXPECT_EQ(median({3, 1, 2}), 2.0);
  EXPECT_EQ(median({4, 1, 3, 2}), 3.0);
}

TEST(RobustRegression, HuberResistsGrossOutliersWhereLeastSquaresDoesNot) {
  std::mt19937 rng(1);
  std::normal_distribution<double> N;
  Design d = random_design(2000, 1, 1, rng);
  for (Eigen::Index i = 0; i < d.r.size(); ++i)
    d.r(i) = 2.0 * d.D(i, 0) + N(rng) + (i % 50 == 0 ? (d.D(i, 0) > 0 ? 30.0 : -30.0) : 0.0); // 2 % outliers
  // Huber bounds an outlier's influence at the threshold (3σ of the noise here): 2 % of outliers at 30σ move least
  // squares by ~0.5 and the Huber estimate by ~0.02·3·E|x|/E[x²] ≈ 0.05 (0.11 with these draws).
  d.scale = 1.0;
  const Fit huber = fit_cols(d, {0}, 3.0);
  const Fit ls = fit_cols(d, {0}, 1e9); // a threshold nothing reaches: least squares
  EXPECT_NEAR(huber.beta(0), 2.0, 0.15);
  EXPECT_GT(std::abs(ls.beta(0) - 2.0), 0.4);
  EXPECT_LT(std::abs(huber.beta(0) - 2.0), 0.25 * std::abs(ls.beta(0) - 2.0));
  EXPECT_LT(huber.loss, fit_cols(d, {}, 3.0).loss);
  // A mask leaves rows out of the fit and of its loss.
  std::vector<char> none(d.r.size(), 0);
  EXPECT_EQ(fit_cols(d, {0}, 3.0, &none).loss, 0.0);
}

// Regressor and error both share a per-cluster component, so rows of a cluster are not independent: the sandwich
// with scores summed per cluster must give the spread of the estimate over repetitions, and per-row clusters must not.
TEST(RobustRegression, ClusteredStandardErrorMatchesTheMonteCarloSpread) {
  std::mt19937 rng(2);
  std::normal_distribution<double> N;
  const int clusters = 100, per = 10, reps = 300;
  std::vector<double> beta, se_clustered, se_rows;
  for (int k = 0; k < reps; ++k) {
    Design d = random_design(clusters, per, 1, rng);
    for (int g = 0; g < clusters; ++g) {
      const double u = N(rng), a = N(rng);
      for (int j = 0; j < per; ++j) {
        const int i = g * per + j;
        d.D(i, 0) = u + 0.5 * d.D(i, 0);
        d.r(i) = 0.3 * d.D(i, 0) + a + 0.5 * N(rng);
      }
    }
    d.scale = robust_scale(d.r);
    const Fit f = fit_cols(d, {0}, 3.0);
    beta.push_back(f.beta(0));
    se_clustered.push_back(std::sqrt(f.cov(0, 0)));
    Design rows = d;
    rows.n_clusters = clusters * per;
    for (int i = 0; i < clusters * per; ++i)
      rows.cluster[i] = i;
    se_rows.push_back(std::sqrt(fit_cols(rows, {0}, 3.0).cov(0, 0)));
  }
  double mean = 0, var = 0, se_c = 0, se_r = 0;
  for (int k = 0; k < reps; ++k)
    mean += beta[k] / reps, se_c += se_clustered[k] / reps, se_r += se_rows[k] / reps;
  for (double b : beta)
    var += (b - mean) * (b - mean) / (reps - 1);
  const double sd = std::sqrt(var);
  EXPECT_NEAR(mean, 0.3, 3 * sd / std::sqrt(double(reps)));
  EXPECT_NEAR(se_c / sd, 1.0, 0.15) << "clustered SE " << se_c << ", Monte-Carlo SD " << sd;
  EXPECT_LT(se_r / sd, 0.7) << "per-row SE " << se_r << " should understate the spread " << sd;
}

TEST(RobustRegression, ChiSquareSurvivalAndGaussianEquivalentSigma) {
  // 5 % quantiles of chi-square (even and odd dof take different closed forms).
  EXPECT_NEAR(chi2_sf(3.841459, 1), 0.05, 1e-6);
  EXPECT_NEAR(chi2_sf(5.991465, 2), 0.05, 1e-6);
  EXPECT_NEAR(chi2_sf(11.070498, 5), 0.05, 1e-6);
  EXPECT_NEAR(chi2_sf(18.307038, 10), 0.05, 1e-6);
  EXPECT_EQ(chi2_sf(0.0, 3), 1.0);
  // One dof: σ = √W. k dof: the σ of the same two-sided p-value; for k = 2, p = exp(−W/2).
  EXPECT_DOUBLE_EQ(wald_to_sigma(25.0, 1), 5.0);
  const double p5 = std::erfc(5.0 / std::sqrt(2.0));
  EXPECT_NEAR(wald_to_sigma(-2.0 * std::log(p5), 2), 5.0, 1e-6);
  EXPECT_EQ(wald_to_sigma(0.0, 9), 0.0);
  EXPECT_EQ(wald_to_sigma(std::nan(""), 9), 0.0);
  // Far past any threshold (p underflows) it stays finite and increasing.
  const double far = wald_to_sigma(3000.0, 9), farther = wald_to_sigma(4000.0, 9);
  EXPECT_TRUE(std::isfinite(far));
  EXPECT_GT(farther, far);
  EXPECT_GT(far, wald_to_sigma(100.0, 9));
}

TEST(RobustRegression, FewClustersTestAgainstFNotChiSquare) {
  // The F reference: known quantiles (t² with 19 dof at p = 0.05 is 2.093²) and the equivalent clusters of a
  // Newey-West covariance (20 clusters, 3 lags: weights 0.75, 0.5, 0.25 → 20 / 2.75 clusters).
  EXPECT_NEAR(f_sf(2.093024 * 2.093024, 1, 19), 0.05, 1e-5);
  EXPECT_NEAR(f_sf(3.521893, 2, 19), 0.05, 1e-5);
  Design d;
  d.n_clusters = 20;
  EXPECT_DOUBLE_EQ(d.wald_df(), 19.0);
  d.hac_lags = 3;
  EXPECT_NEAR(d.wald_df(), 20.0 / 2.75 - 1, 1e-12);
  d.n_clusters = 5000;
  EXPECT_EQ(d.wald_df(), 0.0) << "many clusters: χ²";
  d.n_clusters = 4; // 4 seconds of a smooth series: under two independent clusters, the most cautious reference
  EXPECT_EQ(d.wald_df(), 1.0);
  // Under the null, 8 clusters whose column and errors each share a random effect: the Wald σ of the column past 3σ
  // (two-sided p 0.0027) should be about that rare against F(1, 7); against χ² the covariance's own noise makes it far
  // more common (as a clean 20-s log's accelerometer bias, about 7 clusters' worth, read as an 8.3σ scale error).
  std::mt19937 rng(11);
  std::normal_distribution<double> N;
  const int reps = 4000;
  int past_f = 0, past_chi2 = 0;
  for (int rep = 0; rep < reps; ++rep) {
    Design dr = random_design(8, 25, 1, rng);
    std::vector<double> u(8), v(8); // per cluster: the column's shared part, the errors' shared part
    for (size_t g = 0; g < 8; ++g)
      u[g] = N(rng), v[g] = N(rng);
    for (Eigen::Index i = 0; i < dr.r.size(); ++i) {
      const size_t g = static_cast<size_t>(dr.cluster[i]);
      dr.D(i, 0) = 0.5 * dr.D(i, 0) + u[g];
      dr.r(i) = 0.5 * N(rng) + v[g];
    }
    dr.scale = robust_scale(dr.r);
    const Fit f = fit_cols(dr, {0}, 3.0);
    const double W = f.beta(0) * f.beta(0) / f.cov(0, 0);
    past_f += wald_to_sigma(W, 1, dr.wald_df()) > 3.0;
    past_chi2 += wald_to_sigma(W, 1) > 3.0;
  }
  const double rate_f = double(past_f) / reps, rate_chi2 = double(past_chi2) / reps;
  // Measured: 1.0 % against F (the sandwich of 8 clusters is still a little optimistic), 5.1 % against χ².
  EXPECT_LT(rate_f, 0.015) << "F(1, 7) reference: " << rate_f << " of null fits past 3σ (0.0027 nominal)";
  EXPECT_GT(rate_chi2, 0.03) << "χ² reference: " << rate_chi2 << " (the test could not fail)";
}

TEST(RobustRegression, ShortColumnsTakeThePooledVarianceRatio) {
  // A column that reaches 4 of 40 clusters (a time bin's offset) on the same regressor as one that reaches all (the
  // whole log's offset), errors correlated within clusters. Its cluster-robust variance rests on 4 clusters' scores:
  // under the null its Wald σ passes 3σ (0.27 % nominal) far too often, even against F(1, 39). With the variance ratio
  // of the whole column pooled (Design::pooled_cols) it passes five times less often.
  std::mt19937 rng(5);
  std::normal_distribution<double> N;
  const int reps = 3000, G = 40, per = 25;
  int past_own = 0, past_pooled = 0;
  for (int rep = 0; rep < reps; ++rep) {
    Design d = random_design(G, per, 2, rng);
    std::vector<double> u(G), v(G);
    for (int g = 0; g < G; ++g)
      u[static_cast<size_t>(g)] = N(rng), v[static_cast<size_t>(g)] = N(rng);
    for (Eigen::Index i = 0; i < d.r.size(); ++i) {
      const size_t g = static_cast<size_t>(d.cluster[i]);
      d.D(i, 0) = 0.5 * d.D(i, 0) + u[g];
      d.D(i, 1) = d.cluster[i] < 4 ? d.D(i, 0) : 0.0;
      d.r(i) = 0.5 * N(rng) + v[g];
    }
    d.scale = robust_scale(d.r);
    const Fit own = fit_cols(d, {0, 1}, 3.0);
    d.pooled_cols = {0, 1};
    d.pooled_short = {1};
    const Fit pooled = fit_cols(d, {0, 1}, 3.0);
    EXPECT_DOUBLE_EQ(own.beta(1), pooled.beta(1)); // the estimate is the same, only its covariance differs
    past_own += wald_to_sigma(own.beta(1) * own.beta(1) / own.cov(1, 1), 1, d.wald_df()) > 3.0;
    past_pooled += wald_to_sigma(pooled.beta(1) * pooled.beta(1) / pooled.cov(1, 1), 1, d.wald_df()) > 3.0;
  }
  const double rate_own = double(past_own) / reps, rate_pooled = double(past_pooled) / reps;
  // Measured: 8.0 % with its own variance, 1.5 % pooled (the pooled ratio is itself estimated from 40 clusters).
  EXPECT_GT(rate_own, 0.05) << "own cluster-robust variance: " << rate_own << " (the test could not fail)";
  EXPECT_LT(rate_pooled, 0.025) << "pooled variance ratio: " << rate_pooled << " of null fits past 3σ";
}

TEST(RobustRegression, StepwiseSelectsThePlantedColumnsOnly) {
  std::mt19937 rng(3);
  Design d = random_design(500, 4, 4, rng);
  plant(d, {0.0, 0.5}, 1.0, rng);
  const std::vector<StepCandidate> cands = {{"a", {0}, ""}, {"b", {1}, ""}, {"c", {2, 3}, ""}};
  std::vector<StepResult> res;
  const auto sel = stepwise(d, cands, StepThresholds{}, res);
  ASSERT_EQ(sel, std::vector<size_t>({1}));
  EXPECT_TRUE(res[1].selected);
  EXPECT_FALSE(res[0].selected);
  EXPECT_FALSE(res[2].selected);
  EXPECT_GT(res[1].sigma, 5.0);
  EXPECT_GT(res[1].explained_alone, 0.1);
  EXPECT_LT(res[0].explained_added, 0.02);
  // The estimate comes from the fit and columns the result carries.
  ASSERT_EQ(res[1].joint, std::vector<int>({1}));
  EXPECT_NEAR(res[1].fit.beta(0), 0.5, 0.05);
  // c was last fitted beside b: its own columns follow b's.
  EXPECT_EQ(res[2].joint, std::vector<int>({1, 2, 3}));
}

TEST(RobustRegression, StepwiseExtensionSupersedesTheCandidateItContains) {
  std::mt19937 rng(4);
  Design d = random_design(500, 4, 2, rng);
  plant(d, {1.0, 1.0}, 1.0, rng);
  const std::vector<StepCandidate> cands = {{"const", {0}, ""}, {"drift", {0, 1}, ""}};
  std::vector<StepResult> res;
  const auto sel = stepwise(d, cands, StepThresholds{}, res);
  // const passes first (drift, containing a passing candidate, waits a round); then drift adds its term and takes
  // const's place with const's share added to its own.
  ASSERT_EQ(sel, std::vector<size_t>({1}));
  EXPECT_TRUE(res[1].selected);
  EXPECT_FALSE(res[0].selected);
  EXPECT_EQ(res[0].note, "contained in drift (selected)");
  EXPECT_EQ(res[0].explained_added, 0.0);
  EXPECT_NEAR(res[1].explained_added, res[1].explained_alone, 1e-9); // both: columns {0, 1} against none

  // Only the constant planted: const selected, drift's own term adds nothing.
  plant(d, {1.0}, 1.0, rng);
  const auto sel2 = stepwise(d, cands, StepThresholds{}, res);
  ASSERT_EQ(sel2, std::vector<size_t>({0}));
  EXPECT_FALSE(res[1].selected);
  EXPECT_LT(res[1].sigma, 5.0);
}

TEST(RobustRegression, StepwiseReportsNestedAndSkippedCandidates) {
  std::mt19937 rng(5);
  Design d = random_design(500, 4, 3, rng);
  plant(d, {1.0}, 1.0, rng);
  // "pair" passes through column 0, "one" (column 1 alone) does not: pair is selected and one, whose only column is
  // then in the model, is nested. "later" is skipped and never fitted.
  const std::vector<StepCandidate> cands = {{"pair", {0, 1}, ""}, {"one", {1}, ""}, {"later", {2}, "no data"}};
  std::vector<StepResult> res;
  const auto sel = stepwise(d, cands, StepThresholds{}, res);
  ASSERT_EQ(sel, std::vector<size_t>({0}));
  EXPECT_TRUE(res[1].nested);
  EXPECT_EQ(res[1].note, "nested in a selected candidate: adds no term");
  EXPECT_EQ(res[1].sigma, 0.0);
  EXPECT_EQ(res[2].note, "no data");
  EXPECT_TRUE(res[2].joint.empty());
  EXPECT_EQ(res[2].explained_alone, 0.0);
}

TEST(RobustRegression, BinnedCurveFollowsTheFittedSlope) {
  std::mt19937 rng(6);
  Design d = random_design(4000, 1, 2, rng);
  plant(d, {2.0, -1.0}, 0.1, rng);
  const Fit f = fit_cols(d, {1, 0}, 3.0);
  const ovton::eval::BinnedCurve cur = binned_curve({0}, d, f, {1, 0}, 8);
  EXPECT_NEAR(cur.slope, 2.0, 0.01);
  ASSERT_EQ(cur.x.size(), 8u);
  for (size_t b = 0; b < cur.x.size(); ++b)
    EXPECT_NEAR(cur.mean[b], 2.0 * cur.x[b], 0.05) << "bin " << b; // column 1's effect removed
  // Too few rows for the bins: no curve.
  EXPECT_TRUE(binned_curve({0}, d, f, {1, 0}, 1000).x.empty());
}
