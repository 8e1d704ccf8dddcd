#include "ov_eval/diagnose/unexplained.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

namespace ovton::eval::diag {

namespace {

/// Quantile bin edges of v (n bins).
std::vector<double> quantile_edges(std::vector<double> v, int n) {
  std::sort(v.begin(), v.end());
  std::vector<double> e;
  for (int k = 1; k < n; ++k)
    e.push_back(v.empty() ? 0.0 : v[std::min(v.size() - 1, v.size() * k / n)]);
  return e;
}

const char *const kRegionNames[9] = {"top-left", "top",         "top-right", "left",        "centre",
                                     "right",    "bottom-left", "bottom",    "bottom-right"};

} // namespace

std::vector<UnexplainedStructure> find_unexplained(const Design &d, const std::vector<int> &selected_cols,
                                                   const DiagnoseOptions &opt, const DiagnoseReport &rep) {
  std::vector<UnexplainedStructure> out;
  const Eigen::Index n = d.r.size();
  if (n == 0 || d.region.size() != static_cast<size_t>(n) || d.motion.size() != static_cast<size_t>(n))
    return out;
  // The leftover: what the selected candidates do not explain (their fit, as the selection made it).
  Design left = d;
  left.r = selected_cols.empty() ? d.r : fit_cols(d, selected_cols, opt.huber_k).e;
  const auto speed_edges = quantile_edges(d.motion, 4);
  struct Grouping {
    const char *where;
    int bins;
    std::function<int(Eigen::Index)> bin; ///< −1: row not in this test
    std::function<std::string(int)> name;
  };
  const int time_bins = 6;
  const std::vector<Grouping> groupings = {
      {"time", time_bins,
       [&](Eigen::Index i) {
         return std::min(time_bins - 1, static_cast<int>(time_bins * d.t_s[i] / std::max(1e-9, rep.duration_s)));
       },
       [&](int b) {
         char buf[64];
         std::snprintf(buf, sizeof(buf), "%.0f-%.0f s", b * rep.duration_s / time_bins,
                       (b + 1) * rep.duration_s / time_bins);
         return std::string(buf);
       }},
      {"image region", 9, [&](Eigen::Index i) { return d.region[i]; },
       [](int b) { return std::string(kRegionNames[b]); }},
      {"image speed", 4,
       [&](Eigen::Index i) {
         return static_cast<int>(std::upper_bound(speed_edges.begin(), speed_edges.end(), d.motion[i]) -
                                 speed_edges.begin());
       },
       [&](int b) {
         char buf[64];
         std::snprintf(buf, sizeof(buf), "speed quartile %d (%s px/s)", b + 1,
                       b == 0 ? ("< " + std::to_string(int(speed_edges[0]))).c_str()
                              : ("> " + std::to_string(int(speed_edges[b - 1]))).c_str());
         return std::string(buf);
       }},
  };
  for (const Grouping &g : groupings) {
    // Columns: one mean per bin and component (u rows, v rows), rows outside the test masked out.
    Eigen::MatrixXd X = Eigen::MatrixXd::Zero(n, 2 * g.bins);
    std::vector<char> mask(n, 0);
    for (Eigen::Index i = 0; i < n; ++i) {
      const int b = g.bin(i);
      if (b < 0)
        continue;
      mask[i] = 1;
      X(i, 2 * b + i % 2) = 1.0;
    }
    std::vector<int> used;
    for (int c = 0; c < X.cols(); ++c)
      if (X.col(c).cwiseAbs().sum() >= 40) // a bin mean needs rows to be worth testing
        used.push_back(c);
    if (used.empty())
      continue;
    const double df = left.wald_df();
    if (df > 0 && static_cast<double>(used.size()) > df) { // more bin means than independent clusters to test them
      UnexplainedStructure u;
      u.where = g.where;
      u.testable = false;
      u.largest = "not testable on this log: " + std::to_string(used.size()) + " bin means against about " +
                  std::to_string(static_cast<int>(std::lround(df + 1))) + " independent clusters";
      out.push_back(u);
      continue;
    }
    Eigen::MatrixXd Xu(n, used.size());
    for (size_t c = 0; c < used.size(); ++c)
      Xu.col(c) = X.col(used[c]);
    const Fit f0 = fit_cols(left, {}, opt.huber_k, &mask);
    const Fit f = fit_huber(Xu, left.r, left, opt.huber_k, &mask);
    UnexplainedStructure u;
    u.where = g.where;
    u.explained = f0.loss > 0 ? (f0.loss - f.loss) / f0.loss : 0.0;
    u.sigma = wald_to_sigma(f.beta.dot(f.cov.ldlt().solve(f.beta)), static_cast<int>(used.size()), df);
    u.flagged = u.sigma >= opt.min_sigma && u.explained >= opt.min_explained;
    Eigen::Index big = 0;
    f.beta.cwiseAbs().maxCoeff(&big);
    char buf[160];
    std::snprintf(buf, sizeof(buf), "%s: mean %s %.3f ± %.3f px", g.name(used[big] / 2).c_str(),
                  used[big] % 2 ? "v" : "u", f.beta(big), std::sqrt(std::max(0.0, f.cov(big, big))));
    u.largest = buf;
    out.push_back(u);
  }
  return out;
}

} // namespace ovton::eval::diag
