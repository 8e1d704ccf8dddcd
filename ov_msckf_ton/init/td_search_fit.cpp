#include "ov_msckf_ton/init/td_search_fit.h"
#include "ov_core/math/so3.h"
#include "ov_msckf_ton/init/td_search.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace ovton::msckf {

using ovton::core::GyroIntegral;

namespace {

/// For each pair, the pairs whose interval middles lie within ±half_s of its own: the stretch whose mean is taken away.
std::vector<std::pair<size_t, size_t>> neighbourhoods(const std::vector<PairRate> &pairs, double half_s) {
  std::vector<std::pair<size_t, size_t>> out(pairs.size());
  size_t b = 0, e = 0;
  const auto mid = [&](size_t k) { return 0.5 * (pairs[k].t0 + pairs[k].t1); };
  for (size_t k = 0; k < pairs.size(); ++k) {
    while (mid(b) < mid(k) - half_s)
      ++b;
    while (e < pairs.size() && mid(e) <= mid(k) + half_s)
      ++e;
    out[k] = {b, e};
  }
  return out;
}

/// The rows of one candidate's cost: mean gyro rate over each image interval shifted by t_d, minus the images' rate,
/// high-passed by taking away its mean over the neighbourhood. What the high-pass removes is the gyro bias and the
/// translational flow a rotation fit cannot tell from rotation (lateral motion looks like a turn through a limited
/// field of view: measured 0.15-0.2 rad/s on rendered flights, varying with the velocity, i.e. slowly), while the
/// faster changes of the turn rate, which fix the time, stay.
struct CostEval {
  double cost = 0.0;       ///< Σ w·|h|² with the weights w
  double huber_loss = 0.0; ///< Σ ρ(|h|), ρ Huber with scale c
  std::vector<double> w;
  std::vector<double> norms; ///< |h| per row
};

CostEval evaluate(const std::vector<PairRate> &pairs, const std::vector<std::pair<size_t, size_t>> &hood,
                  const GyroIntegral &gyro, double td, double c, const std::vector<double> *fixed_w = nullptr) {
  const size_t n = pairs.size();
  std::vector<Eigen::Vector3d> r(n), prefix(n + 1, Eigen::Vector3d::Zero());
  for (size_t k = 0; k < n; ++k) {
    r[k] = gyro.mean(pairs[k].t0 + td, pairs[k].t1 + td) - pairs[k].w;
    prefix[k + 1] = prefix[k] + r[k];
  }
  CostEval out;
  out.w.assign(n, 1.0);
  out.norms.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const auto [b, e] = hood[k];
    const double h = out.norms[k] = (r[k] - (prefix[e] - prefix[b]) / static_cast<double>(e - b)).norm();
    out.w[k] = fixed_w ? (*fixed_w)[k] : (h <= c ? 1.0 : c / h);
    out.cost += out.w[k] * h * h;
    out.huber_loss += h <= c ? 0.5 * h * h : c * (h - 0.5 * c);
  }
  return out;
}

/// The standard error of the best candidate when the rows' errors are correlated (sandwich, Bartlett-weighted over
/// `lags` rows): t̂_d − t_d ≈ −J'/J'' with J' = Σ g_k, g_k the derivative of row k's weighted cost, and Var(J') taken
/// from the products of the g_k up to `lags` apart. The curvature alone (2s²/J'') assumes independent rows; but
/// consecutive pairs share an image, the high-pass subtracts a mean over the neighbourhood, and translational flow
/// that a rotation fit takes for rotation varies smoothly. On the built-in agile flight (a 6 m room, walls 1 m away,
/// the attitude oscillating at 3-3.7 rad/s so that the translational flow turns with it) the curvature said
/// −9.6 ± 3.5 ms for a true 10 ms (30-s flight, seed 1); with the correlation ± 7.7 ms, too uncertain to be used
/// (test TdSearchBuiltin.AgileFlightInASmallRoomIsNotConfidentlyWrong; docs/robustness.md, "The coarse search's
/// sigma").
double correlated_sigma(const std::vector<PairRate> &pairs, const std::vector<std::pair<size_t, size_t>> &hood,
                        const GyroIntegral &gyro, double td, double c, const std::vector<double> &w, double curvature,
                        int lags) {
  if (!(curvature > 0))
    return std::numeric_limits<double>::infinity();
  const double dh = 1e-4;
  const CostEval ep = evaluate(pairs, hood, gyro, td + dh, c, &w), em = evaluate(pairs, hood, gyro, td - dh, c, &w);
  std::vector<double> g(pairs.size());
  for (size_t k = 0; k < g.size(); ++k)
    g[k] = w[k] * (ep.norms[k] * ep.norms[k] - em.norms[k] * em.norms[k]) / (2 * dh);
  double V = 0;
  for (int l = 0; l <= lags; ++l) {
    double acc = 0;
    for (size_t k = static_cast<size_t>(l); k < g.size(); ++k)
      acc += g[k] * g[k - static_cast<size_t>(l)];
    V += (l == 0 ? 1.0 : 2.0 * (1.0 - static_cast<double>(l) / (lags + 1))) * acc;
  }
  return V > 0 ? std::sqrt(V) / curvature : 0.0;
}

/// The gyro averaged over a window of one image interval (the median of the pairs'), centred on each reading.
std::vector<ovton::core::ImuData> box_filtered(const ovton::core::ImuBuffer &imu, const std::vector<PairRate> &pairs) {
  std::vector<double> spans;
  for (const auto &p : pairs)
    spans.push_back(p.t1 - p.t0);
  std::nth_element(spans.begin(), spans.begin() + spans.size() / 2, spans.end());
  const int64_t half_ns = ovton::core::s_to_ns(0.5 * spans[spans.size() / 2]);
  std::vector<ovton::core::ImuData> out(imu.begin(), imu.end());
  size_t a = 0, b = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < imu.size(); ++i) {
    while (b < imu.size() && imu[b].t_imu_ns <= imu[i].t_imu_ns + half_ns)
      sum += imu[b++].wm;
    while (imu[a].t_imu_ns < imu[i].t_imu_ns - half_ns)
      sum -= imu[a++].wm;
    out[i].wm = sum / static_cast<double>(b - a);
  }
  return out;
}

double median(std::vector<double> v) {
  if (v.empty())
    return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

} // namespace

/// Rotation R with a_i ≈ R·c_i for unit bearings, by Kabsch with Huber weights (threshold `huber` in radians): far
/// features follow the rotation alone, near ones add parallax, which the weights keep from pulling the fit. (Fitting
/// the translation direction as well, by Gauss-Newton on the epipolar angles, was tried: over 50 ms the lateral
/// translation it should separate looks like rotation through the field of view, and the search's error grew, e.g.
/// from 0.8-1.0 to 1.4-1.6 ms on a rendered V1_02 flight.)
Eigen::Matrix3d fit_rotation(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &c,
                             double huber) {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  std::vector<double> w(a.size(), 1.0);
  for (int iter = 0; iter < 5; ++iter) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    for (size_t i = 0; i < a.size(); ++i)
      H += w[i] * c[i] * a[i].transpose();
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
    R = svd.matrixV() * D * svd.matrixU().transpose();
    for (size_t i = 0; i < a.size(); ++i) {
      const double e = (a[i] - R * c[i]).norm();
      w[i] = e <= huber ? 1.0 : huber / e;
    }
  }
  return R;
}

/// RMS angular acceleration of images [b, e) from the gyro's mean rate per image interval at t_d = prior.
double rms_alpha(const std::vector<double> &t_img, size_t b, size_t e, const GyroIntegral &gyro, double prior) {
  double sum = 0;
  int n = 0;
  for (size_t k = b + 2; k < e; ++k) {
    const double a0 = t_img[k - 2] + prior, a1 = t_img[k - 1] + prior, a2 = t_img[k] + prior;
    if (a0 < gyro.begin() || a2 > gyro.end())
      continue;
    const Eigen::Vector3d alpha = (gyro.mean(a1, a2) - gyro.mean(a0, a1)) / (0.5 * (a2 - a0));
    sum += alpha.squaredNorm();
    ++n;
  }
  return n > 0 ? std::sqrt(sum / n) : 0.0;
}

void fit_offset(std::vector<PairRate> pairs, const ovton::core::ImuBuffer &imu, int64_t t0_ns, double prior_td_s,
                const TdSearchOptions &opt, TdSearchResult &res) {
  const auto finish = [&](const std::string &why) { res.why = why; };
  const GyroIntegral gyro(imu, t0_ns);
  // Every candidate must see the same pairs: keep those the gyro covers over the whole search range.
  pairs.erase(std::remove_if(pairs.begin(), pairs.end(),
                             [&](const PairRate &p) {
                               return p.t0 + prior_td_s - opt.range_s < gyro.begin() ||
                                      p.t1 + prior_td_s + opt.range_s > gyro.end();
                             }),
              pairs.end());
  res.pairs = static_cast<int>(pairs.size());
  if (res.pairs < opt.min_pairs)
    return finish("only " + std::to_string(res.pairs) + " image pairs with a rotation fit inside the IMU log");

  const auto hood = neighbourhoods(pairs, 0.5 * opt.highpass_s);
  double mean_hood = 0;
  for (const auto &[b, e] : hood)
    mean_hood += static_cast<double>(e - b) / static_cast<double>(hood.size());

  // Pass 1, least squares on the grid (c = inf); its residuals set the Huber scale of pass 2.
  const int n_steps = static_cast<int>(std::round(opt.range_s / opt.step_s));
  const double inf = std::numeric_limits<double>::infinity();
  const auto grid_best = [&](double c, std::vector<double> *profile) {
    double best = inf, best_td = prior_td_s;
    for (int s = -n_steps; s <= n_steps; ++s) {
      const double td = prior_td_s + s * opt.step_s;
      const double J = evaluate(pairs, hood, gyro, td, c).huber_loss;
      if (profile)
        profile->push_back(J);
      if (J < best) {
        best = J;
        best_td = td;
      }
    }
    return best_td;
  };
  const double td1 = grid_best(inf, nullptr);
  // Scale of the rows at the least-squares optimum (MAD of their norms), for the Huber threshold.
  const double scale = std::max(1e-3, 1.4826 * median(evaluate(pairs, hood, gyro, td1, inf).norms));
  const double c = 2.0 * scale;
  std::vector<double> profile;
  double td2 = grid_best(c, &profile);
  // Refine: 0.1 ms steps around the best grid point.
  {
    double best = inf;
    const double centre = td2;
    for (int s = -20; s <= 20; ++s) {
      const double td = centre + s * 1e-4;
      const double J = evaluate(pairs, hood, gyro, td, c).huber_loss;
      if (J < best) {
        best = J;
        td2 = td;
      }
    }
  }
  res.td_s = td2;

  // Standard error from the curvature of the weighted least-squares cost at the minimum (weights fixed there):
  // σ² = 2·s²/J'', s² the residual variance per row; or, where larger, from the rows' correlated scores
  // (correlated_sigma). Both again with the gyro averaged over one image interval: the images cannot follow faster
  // rotation, and the gyro's vibration (10-40 Hz on the EuRoC IMU) sharpens the cost's curvature around its minimum
  // without saying where the images' rates line up (docs/robustness.md, "The coarse search's sigma").
  const int lags = static_cast<int>(std::ceil(mean_hood));
  struct Sigmas {
    double curvature, correlated, s2, huber_loss;
  };
  const auto sigmas_with = [&](const GyroIntegral &g) {
    const CostEval at = evaluate(pairs, hood, g, td2, c);
    const double h = 0.002;
    const double Jp = evaluate(pairs, hood, g, td2 + h, c, &at.w).cost,
                 Jm = evaluate(pairs, hood, g, td2 - h, c, &at.w).cost;
    const double curvature = (Jp - 2 * at.cost + Jm) / (h * h);
    double sw = 0;
    for (double w : at.w)
      sw += w;
    // Per row and axis; the high-pass takes away 1/m of white noise's variance (m rows per neighbourhood).
    const double s2_g = at.cost / std::max(1.0, 3 * sw * (1 - 1 / mean_hood) - 1);
    return Sigmas{curvature > 0 ? std::sqrt(2 * s2_g / curvature) : inf,
                  correlated_sigma(pairs, hood, g, td2, c, at.w, curvature, lags), s2_g, at.huber_loss};
  };
  const Sigmas raw = sigmas_with(gyro), slow = sigmas_with(GyroIntegral(box_filtered(imu, pairs), t0_ns));
  res.sigma_s = std::max({raw.curvature, raw.correlated, slow.curvature, slow.correlated});
  const double s2 = raw.s2;
  res.residual_sigma = std::sqrt(s2);
  res.cost_profile = profile;

  // A second valley anywhere else in the range that the data cannot tell from the best one makes the answer a guess:
  // the lowest local minimum of the profile farther from the best than its own valley plausibly reaches.
  const double sep = std::max(0.01, 4 * res.sigma_s);
  double rival = inf;
  for (int i = 0; i < static_cast<int>(profile.size()); ++i) {
    const bool local_min = (i == 0 || profile[i - 1] >= profile[i]) &&
                           (i + 1 == static_cast<int>(profile.size()) || profile[i + 1] >= profile[i]);
    if (local_min && std::abs(prior_td_s + (i - n_steps) * opt.step_s - td2) > sep)
      rival = std::min(rival, profile[i]);
  }
  const double best_loss = raw.huber_loss;
  char why[200];
  if (std::abs(td2 - prior_td_s) > opt.range_s - 2 * opt.step_s) {
    std::snprintf(why, sizeof why, "best candidate %.1f ms at the edge of the range: the offset may lie beyond it",
                  td2 * 1e3);
    return finish(why);
  }
  if (!(res.sigma_s <= opt.max_sigma_s)) {
    std::snprintf(why, sizeof why, "best candidate %.1f ms too uncertain (sigma %.1f ms)", td2 * 1e3,
                  res.sigma_s * 1e3);
    return finish(why);
  }
  // Twice the loss difference over the residual variance is a chi-square-like statistic (the Huber loss is half the
  // squared residual inside c): under 25 (5 sigma) the rival valley cannot be excluded.
  if (2 * (rival - best_loss) / s2 < 25) {
    std::snprintf(why, sizeof why, "ambiguous: another minimum fits almost as well as %.1f ms", td2 * 1e3);
    return finish(why);
  }
  res.found = true;
}

} // namespace ovton::msckf
