#include "ov_eval/diagnose.h"
#include "ov_core/cam/camera_model.h"
#include "ov_core/io/csv.h"
#include "ov_core/io/text_format.h"
#include "ov_core/math/so3.h"
#include "ov_core/types/errors.h"
#include "ov_eval/plot.h"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <numeric>
#include <sstream>

namespace ov_eval {

// ---------------------------------------------------------------------------------------------------------------
// Regression machinery
// ---------------------------------------------------------------------------------------------------------------

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

/// Columns of the design matrix; a candidate is a list of them, so nested candidates share columns.
enum Col : int {
  kV = 0,                  ///< image velocity [px/s]
  kVt,                     ///< image velocity × (t − t_mid) [px]
  kVrow,                   ///< image velocity × (row fraction − 0.5) [px/s]
  kFocal,                  ///< (fu·x, fv·y) [px]
  kPpU,                    ///< (1, 0)
  kPpV,                    ///< (0, 1)
  kRadial,                 ///< r²·(fu·x, fv·y) [px]
  kGyro0,                  ///< 9 columns B(x,y)·e_i·Θ_j [px·rad/rad]
  kGyroScale = kGyro0 + 9, ///< with the camera: −B(x,y)·R_CB·Θ [px], the nine above contracted with R_CB
  kNumCols
};

struct Design {
  MatrixXd D;               ///< n × kNumCols, demeaned per track where the column says so
  VectorXd r;               ///< residual components, u and v rows interleaved
  std::vector<int> cluster; ///< track index per component row
  std::vector<double> t_s;  ///< time of each component row [s from the first used row]
  int n_clusters = 0;
  double scale = 1; ///< robust σ of r
  double t_mid = 0; ///< centre of the drift term
  bool have_velocity = false, have_rate = false;
};

struct Fit {
  VectorXd beta;
  MatrixXd cov;
  double loss = 0;
  VectorXd e; ///< final residual
};

double huber_rho(double e, double c) {
  const double a = std::abs(e);
  return a <= c ? 0.5 * e * e : c * a - 0.5 * c * c;
}

/// Huber M-estimate by IRLS with a fixed scale (so that losses of different candidates compare), and its
/// covariance by the sandwich with scores summed per track: residuals of one track share the triangulated point and
/// are not independent, so per-row standard errors would be too small.
Fit fit_huber(const MatrixXd &X, const VectorXd &r, const Design &d, double k,
              const std::vector<char> *mask = nullptr) {
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
    f.cov = g * Ainv * (S.transpose() * S) * Ainv;
  }
  return f;
}

/// Survival function of chi-square with k degrees of freedom (closed forms for integer k).
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

/// Wald statistic with k dof as the two-sided Gaussian σ of the same p-value, so that "5σ" means the same thing for
/// a one-parameter and a nine-parameter candidate.
double wald_to_sigma(double W, int k) {
  if (!(W > 0) || k <= 0)
    return 0.0;
  if (k == 1)
    return std::sqrt(W);
  const double p = chi2_sf(W, k);
  if (!(p > 1e-300))
    return std::sqrt(std::max(0.0, W - (k - 1) * std::log(W))); // far past any threshold; a monotone stand-in
  double lo = 0, hi = 40;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

struct CandidateDef {
  std::string key, description;
  std::vector<int> cols;
  bool needs_velocity = false, needs_rate = false;
};

std::vector<CandidateDef> candidate_defs() {
  std::vector<int> gyro;
  for (int i = 0; i < 9; ++i)
    gyro.push_back(kGyro0 + i);
  return {
      {"td_const", "constant time-offset error: r = V·δt", {kV}, true, false},
      {"td_drift", "drifting time-offset error: r = V·(δt + ḋ·(t − t_mid))", {kV, kVt}, true, false},
      {"rolling_shutter", "rolling-shutter readout: r = V·(row/height − 0.5)·t_r", {kVrow}, true, false},
      {"focal", "focal-length error: r = ε·(fu·x, fv·y), δf = ε·f", {kFocal}, false, false},
      {"principal_point", "principal-point error: r = (δcu, δcv)", {kPpU, kPpV}, false, false},
      {"radial_k1", "radial distortion error: r = δk1·|xy|²·(fu·x, fv·y)", {kRadial}, false, false},
      {"gyro_scale", "gyro scale error: r = −s·B(x,y)·R_CB·∫ω dt over the track", gyro, false, true},
  };
}

/// Rotational image flow of a normalised point per unit camera rotation (columns: rotation about x, y, z).
Eigen::Matrix<double, 2, 3> rot_flow(double x, double y) {
  Eigen::Matrix<double, 2, 3> B;
  B << x * y, -(1 + x * x), y, 1 + y * y, -x * y, -x;
  return B;
}

/// Replaces every column x of X, within each track (rows [begin, end) of one cluster), by x − J·(J⁺x): what the
/// track's triangulated point could not absorb. J (2m × 3) is the track's point Jacobian.
void project_out_points(const MatrixXd &J_point, const std::vector<int> &cluster, MatrixXd &X) {
  const Eigen::Index n = X.rows();
  for (Eigen::Index i0 = 0; i0 < n;) {
    Eigen::Index i1 = i0;
    while (i1 < n && cluster[i1] == cluster[i0])
      ++i1;
    // Rank-revealing: under pure rotation (or without parallax) the point's depth changes nothing, J has rank 2, and a
    // plain QR would remove an arbitrary third direction.
    Eigen::ColPivHouseholderQR<MatrixXd> qr(J_point.middleRows(i0, i1 - i0));
    qr.setThreshold(1e-9);
    const MatrixXd Q1 = qr.householderQ() * MatrixXd::Identity(i1 - i0, qr.rank());
    X.middleRows(i0, i1 - i0) -= Q1 * (Q1.transpose() * X.middleRows(i0, i1 - i0));
    i0 = i1;
  }
}

/// Derivative at t of the parabola through (t0, x0), (t1, x1), (t2, x2) (distinct times).
Eigen::Vector2d lagrange_derivative(double t0, double t1, double t2, const Eigen::Vector2d &x0,
                                    const Eigen::Vector2d &x1, const Eigen::Vector2d &x2, double t) {
  const double l0 = ((t - t1) + (t - t2)) / ((t0 - t1) * (t0 - t2));
  const double l1 = ((t - t0) + (t - t2)) / ((t1 - t0) * (t1 - t2));
  const double l2 = ((t - t0) + (t - t1)) / ((t2 - t0) * (t2 - t1));
  return l0 * x0 + l1 * x1 + l2 * x2;
}

double median(std::vector<double> v) {
  if (v.empty())
    return 0;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + m, v.end());
  return v[m];
}

std::vector<EffectEstimate> estimates_of(const std::string &key, const std::vector<int> &cols, const Fit &fit,
                                         const std::vector<int> &joint, const DiagnoseReport &rep, const Design &d) {
  std::vector<int> at;
  for (int c : cols)
    at.push_back(static_cast<int>(std::find(joint.begin(), joint.end(), c) - joint.begin()));
  const auto b = [&](int i) { return fit.beta(at[i]); };
  const auto s = [&](int i) { return std::sqrt(std::max(0.0, fit.cov(at[i], at[i]))); };
  std::vector<EffectEstimate> out;
  if (key == "td_const") {
    out.push_back({"offset error δt", "ms", 1e3 * b(0), 1e3 * s(0)});
  } else if (key == "td_drift") {
    const double t0 = -d.t_mid; // start of the log relative to the centre
    const double v = fit.cov(at[0], at[0]) + t0 * t0 * fit.cov(at[1], at[1]) + 2 * t0 * fit.cov(at[0], at[1]);
    out.push_back({"drift rate", "ms/s", 1e3 * b(1), 1e3 * s(1)});
    out.push_back({"offset error at start", "ms", 1e3 * (b(0) + t0 * b(1)), 1e3 * std::sqrt(std::max(0.0, v))});
    out.push_back({"offset error at mid-log", "ms", 1e3 * b(0), 1e3 * s(0)});
  } else if (key == "rolling_shutter") {
    out.push_back({"readout time t_r", "ms", 1e3 * b(0), 1e3 * s(0)});
  } else if (key == "focal") {
    const double f = 0.5 * (rep.fu + rep.fv);
    out.push_back({"focal error δf", "px", f * b(0), f * s(0)});
    out.push_back({"relative focal error ε", "%", 100 * b(0), 100 * s(0)});
  } else if (key == "principal_point") {
    out.push_back({"δcu", "px", b(0), s(0)});
    out.push_back({"δcv", "px", b(1), s(1)});
  } else if (key == "radial_k1") {
    out.push_back({"δk1", "", b(0), s(0)});
  } else if (key == "gyro_scale" && cols.size() == 1) { // R_CB known: the column is −ω̄_gyro or −B·R_CB·Θ
    out.push_back({"gyro scale error s", "%", 100 * b(0), 100 * s(0)});
  } else if (key == "gyro_scale") {
    // M = −s·R_CB: |M|_F = √3·|s| and det M = −s³, so s = −sign(det M)·|M|_F/√3 (delta-method σ).
    Eigen::Matrix3d M;
    Eigen::Matrix<double, 9, 9> C;
    for (int i = 0; i < 9; ++i) {
      M(i / 3, i % 3) = b(i);
      for (int j = 0; j < 9; ++j)
        C(i, j) = fit.cov(at[i], at[j]);
    }
    const double nrm = M.norm();
    const double sgn = M.determinant() > 0 ? -1.0 : 1.0;
    Eigen::Matrix<double, 9, 1> g;
    for (int i = 0; i < 9; ++i)
      g(i) = nrm > 0 ? sgn * M(i / 3, i % 3) / (nrm * std::sqrt(3.0)) : 0.0;
    out.push_back({"gyro scale error s", "%", 100 * sgn * nrm / std::sqrt(3.0),
                   100 * std::sqrt(std::max(0.0, double(g.transpose() * C * g)))});
  }
  return out;
}

Fit fit_cols(const Design &d, const std::vector<int> &cols, double k, const std::vector<char> *mask = nullptr) {
  MatrixXd X(d.r.size(), cols.size());
  for (size_t j = 0; j < cols.size(); ++j)
    X.col(j) = d.D.col(cols[j]);
  return fit_huber(X, d.r, d, k, mask);
}

/// Partial residual (other selected effects removed) binned against the candidate's own variable.
BinnedCurve make_curve(const CandidateDef &c, const Design &d, const Fit &fit, const std::vector<int> &joint,
                       int bins) {
  BinnedCurve cur;
  const Eigen::Index n = d.r.size();
  VectorXd own = VectorXd::Zero(n), x(n);
  for (size_t j = 0; j < joint.size(); ++j)
    if (std::find(c.cols.begin(), c.cols.end(), joint[j]) != c.cols.end())
      own += fit.beta(j) * d.D.col(joint[j]);
  const VectorXd y = fit.e + own; // residual with everything but this effect removed
  if (c.cols.size() == 1) {
    x = d.D.col(c.cols[0]);
    const std::vector<int> one = {c.cols[0]};
    const auto it = std::find(joint.begin(), joint.end(), c.cols[0]) - joint.begin();
    cur.slope = fit.beta(it);
  } else {
    x = own;
    cur.slope = 1.0;
  }
  static const std::map<std::string, std::string> xl = {
      {"td_const", "image velocity V [px/s]"},
      {"rolling_shutter", "V * (row fraction - 0.5) [px/s]"},
      {"focal", "image position from the centre (f * x), point-absorbed part removed [px]"},
      {"radial_k1", "|x|^2 * f * x, point-absorbed part removed [px]"}};
  cur.xlabel = xl.count(c.key) ? xl.at(c.key) : "fitted " + c.key + " effect [px]";
  cur.ylabel = "residual, other selected effects removed [px] (bin mean +- SE)";
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

using TrackMap = std::map<std::pair<uint64_t, uint64_t>, std::vector<const ResidualLogRow *>>;

/// Forward stepwise selection among `family` (indices into defs) on design d; fills res[c] for each member and returns
/// the selected ones in selection order. A candidate that strictly contains a passing one (drift ⊃ constant offset)
/// waits a round and, when selected later, takes the contained one's place.
std::vector<size_t> stepwise(const Design &d, const std::vector<CandidateDef> &defs, const std::vector<size_t> &family,
                             const DiagnoseOptions &opt, const DiagnoseReport &rep, std::vector<CandidateResult> &res) {
  std::vector<size_t> order;
  if (family.empty())
    return order;
  const double k = opt.huber_k;
  const double loss0 = fit_cols(d, {}, k).loss;
  // A candidate's shares are of the loss of the rows it predicts (non-zero in one of its columns): on rates, the ω
  // rows and the ψ rows are different data, and a candidate predicting one kind is not diluted by the other.
  std::vector<double> own_loss0(defs.size(), loss0), gain(defs.size(), 0.0);
  for (size_t c : family) {
    std::vector<char> mask(d.r.size(), 0);
    for (Eigen::Index i = 0; i < d.r.size(); ++i)
      for (int col : defs[c].cols)
        mask[i] = mask[i] || d.D(i, col) != 0.0;
    own_loss0[c] = std::max(1e-300, fit_cols(d, {}, k, &mask).loss);
  }
  std::vector<bool> usable(defs.size(), false), taken(defs.size(), false);
  for (size_t c : family) {
    usable[c] = true;
    if (defs[c].needs_velocity && !d.have_velocity) {
      usable[c] = false;
      res[c].note = "skipped: fewer than " + std::to_string(int(100 * opt.min_velocity_share)) +
                    "% of rows carry an image velocity";
    }
    if (defs[c].needs_rate && !d.have_rate) {
      usable[c] = false;
      res[c].note = "skipped: most tracks lack body rates (w_valid)";
    }
    if (usable[c])
      res[c].explained_alone = (loss0 - fit_cols(d, defs[c].cols, k).loss) / own_loss0[c];
  }
  std::vector<int> selected_cols;
  double loss_sel = loss0;
  std::vector<Fit> last_fit(defs.size());
  std::vector<std::vector<int>> last_joint(defs.size());
  const auto strictly_contains = [&](size_t a, size_t b) {
    if (defs[a].cols.size() <= defs[b].cols.size())
      return false;
    for (int col : defs[b].cols)
      if (std::find(defs[a].cols.begin(), defs[a].cols.end(), col) == defs[a].cols.end())
        return false;
    return true;
  };
  while (true) {
    int best = -1;
    std::vector<bool> passes(defs.size(), false);
    for (size_t c : family) {
      if (!usable[c] || taken[c])
        continue;
      std::vector<int> joint = selected_cols, own;
      for (int col : defs[c].cols)
        if (std::find(joint.begin(), joint.end(), col) == joint.end())
          joint.push_back(col), own.push_back(col);
      CandidateResult &cr = res[c];
      if (own.empty()) {
        cr.explained_added = 0, cr.sigma = 0;
        cr.note = "nested in a selected candidate: adds no term";
        last_fit[c] = Fit();
        last_joint[c].clear();
        continue;
      }
      const Fit f = fit_cols(d, joint, k);
      const Eigen::Index q = static_cast<Eigen::Index>(own.size());
      const VectorXd bo = f.beta.tail(q);
      const MatrixXd Co = f.cov.bottomRightCorner(q, q);
      const double W = bo.dot(Co.ldlt().solve(bo));
      cr.sigma = wald_to_sigma(W, static_cast<int>(q));
      gain[c] = loss_sel - f.loss;
      cr.explained_added = gain[c] / own_loss0[c];
      cr.estimates = estimates_of(defs[c].key, defs[c].cols, f, joint, rep, d);
      last_fit[c] = f;
      last_joint[c] = joint;
      passes[c] = cr.sigma >= opt.min_sigma && cr.explained_added >= opt.min_explained;
    }
    for (size_t c : family) {
      if (!passes[c])
        continue;
      bool nests = false;
      for (size_t b : family)
        nests = nests || (b != c && passes[b] && strictly_contains(c, b));
      if (!nests && (best < 0 || res[c].explained_added > res[best].explained_added))
        best = static_cast<int>(c);
    }
    if (best < 0)
      break;
    taken[best] = true;
    res[best].explained = true;
    loss_sel -= gain[best];
    // A selected extension (drift) supersedes the candidate it contains (constant offset): it takes that one's rank
    // and the contained one is no longer the name of the effect.
    for (size_t q = 0; q < order.size(); ++q)
      if (strictly_contains(best, order[q])) {
        res[order[q]].explained = false;
        res[order[q]].note = "contained in " + defs[best].key + " (selected)";
        res[best].explained_added += res[order[q]].explained_added;
        res[order[q]].explained_added = 0;
        order.erase(order.begin() + q);
        break;
      }
    res[best].curve = make_curve(defs[best], d, last_fit[best], last_joint[best], opt.plot_bins);
    order.push_back(best);
    for (int col : defs[best].cols)
      if (std::find(selected_cols.begin(), selected_cols.end(), col) == selected_cols.end())
        selected_cols.push_back(col);
  }
  for (size_t c : family)
    if (!taken[c] && usable[c] && !last_joint[c].empty())
      res[c].curve = make_curve(defs[c], d, last_fit[c], last_joint[c], opt.plot_bins);
  return order;
}

/// Rows of the rate design per image: ω_vis − ω_gyro, ψ_vis and ω_vis − ω̄_gyro (the gyro through the images'
/// estimator), three axes each.
constexpr int kRateRowsPerImage = 9;

/// The shifts of an undistorted normalised point x per unit relative focal error ε and per unit δk1. Both act on the
/// distorted point and the filter undistorts, so each is the distorted change mapped through the inverse of the
/// distortion's Jacobian: J_d⁻¹·x_d and J_d⁻¹·|x|²·x (x and |x|²·x without a camera model).
struct ErrorDirs {
  Eigen::Vector2d focal, k1;
};
ErrorDirs error_dirs(const ov_core::CameraModel *cam, const Eigen::Vector2d &x) {
  const Eigen::Vector2d k1 = x.squaredNorm() * x;
  if (!cam)
    return {x, k1};
  Eigen::Matrix2d Jd;
  const Eigen::Vector2d xd = cam->distort_normalized(x, &Jd);
  const Eigen::PartialPivLU<Eigen::Matrix2d> lu(Jd);
  return {lu.solve(xd), lu.solve(k1)};
}
Eigen::Vector2d focal_dir(const ov_core::CameraModel *cam, const Eigen::Vector2d &x) {
  return error_dirs(cam, x).focal;
}

/// Gyro reading at t (linear interpolation; clamped at the ends).
Eigen::Vector3d gyro_at(const std::vector<ov_core::ImuData> &imu, double t_ns) {
  const auto it = std::lower_bound(imu.begin(), imu.end(), t_ns,
                                   [](const ov_core::ImuData &m, double t) { return double(m.t_imu_ns) < t; });
  if (it == imu.begin())
    return imu.front().wm;
  if (it == imu.end())
    return imu.back().wm;
  const auto &a = *(it - 1), &b = *it;
  const double u = (t_ns - double(a.t_imu_ns)) / double(b.t_imu_ns - a.t_imu_ns);
  return a.wm + u * (b.wm - a.wm);
}

/// The design of the candidates tested on rates. Per image, the measured image velocities of its features (their
/// depths corrected per track) are fitted with the flow model ẋ = B(x)·(ω + ρ·ψ) + A(x)·v/z, ρ the row fraction − ½:
/// ω is the camera's angular rate seen at the image's middle row, ψ its change from the top row to the bottom one.
/// Nine rows per image (kRateRowsPerImage), whitened per axis by the fit's standard errors:
///  - ω_vis − ω_gyro at the filter's image time t_cam + t̂_d. A time-offset error δt = t_d − t̂_d shows as α·δt, α the
///    angular acceleration; the gyro bias b is removed per 5-s bin.
///  - ψ_vis: a rolling shutter exposes row ρ at (ρ + ½)·t_r after row 0, so the rate changes down the image by
///    ψ = α·t_r. Nothing in a filter's state can produce it.
///  - ω_vis − ω̄_gyro, the gyro through the images' estimator: a relative focal error ε scales the images' rotational
///    flow but not the gyro's; its column is the response of ω_vis to ε through the whole fit.
/// Measured image velocities (not predicted ones) keep the filter's state out of it.
bool build_rate_design(TrackMap &tracks, const DiagnoseOptions &opt, const DiagnoseReport &rep, int64_t t_first,
                       Design &dr, std::string &why) {
  struct FlowObs {
    Eigen::Vector2d x, xdot;
    double rho, inv_z;
    size_t track;
    int n_win = 0;                     ///< positions in the slope's window
    std::array<double, 5> win_t_imu{}; ///< their IMU-clock times [ns]
    std::array<double, 5> win_w{};     ///< the slope's weight on each: ẋ = Σ w_q·x_q
    double t_imu = 0;                  ///< this observation's IMU-clock time [ns]
  };
  std::map<int64_t, std::vector<FlowObs>> frames;
  size_t n_tracks = 0;
  std::map<int64_t, double> frame_td;
  for (auto &kv : tracks) {
    const auto &tr = kv.second;
    const size_t m = tr.size();
    for (size_t j = 1; j + 1 < m; ++j) {
      const ResidualLogRow *r = tr[j];
      if (!(std::isfinite(r->depth_m) && r->depth_m > 0))
        continue;
      // Local slope of a quadratic through up to five measured positions around j (least squares): linear in the
      // positions, ẋ = Σ w_q·x_q, and the weights are kept to put the gyro through the same slope.
      const size_t a = j >= 2 ? j - 2 : 0, b = std::min(m - 1, j + 2);
      const auto h = [&](size_t q) {
        const double tau = 1e-9 * double(tr[q]->t_cam_ns - r->t_cam_ns);
        return Eigen::Vector3d(1.0, tau, tau * tau);
      };
      Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
      for (size_t q = a; q <= b; ++q)
        A += h(q) * h(q).transpose();
      const Eigen::LDLT<Eigen::Matrix3d> Al(A);
      FlowObs o{Eigen::Vector2d(r->x_norm, r->y_norm), Eigen::Vector2d::Zero(), r->v_px / rep.image_height - 0.5,
                1.0 / r->depth_m, n_tracks};
      for (size_t q = a; q <= b; ++q) {
        o.win_t_imu[o.n_win] = double(tr[q]->t_cam_ns) + 1e9 * tr[q]->td_s;
        o.win_w[o.n_win] = Al.solve(h(q))(1);
        o.xdot += o.win_w[o.n_win++] * Eigen::Vector2d(tr[q]->x_norm, tr[q]->y_norm);
      }
      o.t_imu = double(r->t_cam_ns) + 1e9 * r->td_s;
      frames[r->t_cam_ns].push_back(o);
      frame_td[r->t_cam_ns] = r->td_s;
    }
    ++n_tracks;
  }
  const Eigen::Matrix3d R_BC = opt.camera.T_BC.block<3, 3>(0, 0);
  const ov_core::CameraModel cam(opt.camera);
  using Vec9 = Eigen::Matrix<double, 9, 1>;
  // The flow model's rows for one feature: ẋ = H·(ω, ψ, v).
  const auto flow_rows = [](const Eigen::Vector2d &x, double rho, double iz) {
    Eigen::Matrix<double, 2, 9> H;
    H.leftCols<3>() = rot_flow(x.x(), x.y());
    H.middleCols<3>(3) = rho * H.leftCols<3>();
    H.rightCols<3>() << -iz, 0, x.x() * iz, 0, -iz, x.y() * iz;
    return H;
  };
  struct FrameRate {
    double t;                     ///< s from t_first
    Eigen::Vector3d e, alpha, se; ///< ω_vis − ω_gyro (body frame), α, SE of ω_vis
    Eigen::Vector3d psi, psi_se;  ///< ψ_vis (body frame) and its SE
    Eigen::Vector3d focal_e;      ///< response of ω_vis to a unit relative focal error
    Eigen::Vector3d gyro_s, e_s;  ///< ω̄_gyro, the gyro through the images' estimator, and ω_vis − ω̄_gyro
  };
  std::vector<FrameRate> fr;
  const double h_ns = 50e6; // ±50 ms for the angular acceleration: the gyro noise of a difference shrinks with it
  // The logged depths ẑ come from the filter's triangulation. A filter holding a wrong offset triangulates with poses
  // from the wrong instant, and its points take up part of the offset: their depth errors would let the translational
  // flow absorb part of the rotation an offset error adds (measured: 30 ms read as 15-23 ms, docs/diagnose.md). Each
  // track's inverse depth therefore gets a correction ε_track, alternated with the per-image fits: per image (ω, ψ, v)
  // by Huber IRLS on the flow model with inverse depths 1/ẑ + ε_track, then every ε_track by weighted least squares on
  // what the images' translational flow leaves of its observations.
  std::vector<double> eps(n_tracks, 0.0);
  struct FrameFit {
    Vec9 sol, focal; ///< fitted (ω, ψ, v) and its response to a unit relative focal error
    Eigen::Matrix<double, 9, 9> C;
    VectorXd w;
  };
  // One image's flow design with the current depth corrections: (ω, ψ, v), or (ω, v) without ψ.
  const auto frame_design = [&](const std::vector<FlowObs> &obs, bool with_psi) {
    const Eigen::Index no = static_cast<Eigen::Index>(obs.size());
    MatrixXd H(2 * no, with_psi ? 9 : 6);
    for (Eigen::Index q = 0; q < no; ++q) {
      const Eigen::Matrix<double, 2, 9> Hq = flow_rows(obs[q].x, obs[q].rho, obs[q].inv_z + eps[obs[q].track]);
      if (with_psi)
        H.middleRows<2>(2 * q) = Hq;
      else
        H.middleRows<2>(2 * q) << Hq.leftCols<3>(), Hq.rightCols<3>();
    }
    return H;
  };
  // with_psi false: ψ fixed at 0, so ω is the rate at the features' mean row (what the time candidates compare with
  // the gyro; fitting ψ as well costs ω precision where the features do not span the rows evenly).
  const auto fit_frame = [&](const std::vector<FlowObs> &obs, bool with_psi) {
    const Eigen::Index no = static_cast<Eigen::Index>(obs.size());
    const int p = with_psi ? 9 : 6;
    const MatrixXd H = frame_design(obs, with_psi);
    VectorXd y(2 * no);
    FrameFit f;
    f.w = VectorXd::Ones(2 * no);
    for (Eigen::Index q = 0; q < no; ++q)
      y.segment<2>(2 * q) = obs[q].xdot;
    // The solution and its covariance in the 9 parameters (ψ rows and columns zero without ψ).
    const auto expand = [&](const VectorXd &v) {
      Vec9 out = Vec9::Zero();
      if (with_psi)
        out = v;
      else
        out << v.head<3>(), Eigen::Vector3d::Zero(), v.tail<3>();
      return out;
    };
    double s2 = 0;
    Eigen::LDLT<MatrixXd> N;
    for (int it = 0; it < 3; ++it) { // Huber IRLS, scale from the previous pass
      const MatrixXd Hw = f.w.asDiagonal() * H;
      N.compute(H.transpose() * Hw);
      const VectorXd sol = N.solve(Hw.transpose() * y);
      f.sol = expand(sol);
      const VectorXd e = y - H * sol;
      std::vector<double> ae(e.size());
      for (Eigen::Index q = 0; q < e.size(); ++q)
        ae[q] = std::abs(e(q));
      const double sc = std::max(1e-12, 1.4826 * median(ae));
      s2 = sc * sc;
      for (Eigen::Index q = 0; q < e.size(); ++q)
        f.w(q) = std::abs(e(q)) <= 3 * sc ? 1.0 : 3 * sc / std::abs(e(q));
    }
    const MatrixXd Hw = f.w.asDiagonal() * H;
    N.compute(H.transpose() * Hw);
    const MatrixXd C = s2 * N.solve(MatrixXd::Identity(p, p));
    f.C.setZero();
    for (int a = 0; a < p; ++a)
      f.C.col(with_psi || a < 3 ? a : a + 3) = expand(C.col(a));
    return f;
  };
  using FrameMap = std::map<int64_t, std::vector<FlowObs>>;
  const auto solve = [&](const FrameMap &data, std::map<int64_t, FrameFit> &fits,
                         std::map<int64_t, FrameFit> &fits_psi) {
    std::fill(eps.begin(), eps.end(), 0.0);
    const int n_alternations = 10; // measured: 10 and 30 give the same estimates within a tenth of their SE
    for (int outer = 0; outer <= n_alternations; ++outer) {
      const bool last = outer == n_alternations;
      fits_psi.clear();
      for (const auto &[t_cam, obs] : data) {
        if (obs.size() >= 12 && last)
          fits[t_cam] = fit_frame(obs, false);
        if (obs.size() >= 20) // ψ needs features spread over the rows
          fits_psi[t_cam] = fit_frame(obs, true);
        else if (obs.size() >= 12 && !last)
          fits_psi[t_cam] = fit_frame(obs, false);
      }
      if (last)
        break;
      // ε per track: least squares of what the translational flow leaves, given every image's (ω, ψ, v). With ψ: a
      // rolling shutter's row-dependent flow would otherwise go into the depths of tracks at different rows.
      std::vector<double> num(n_tracks, 0.0), den(n_tracks, 0.0);
      for (const auto &[t_cam, f] : fits_psi) {
        const auto &obs = data.at(t_cam);
        for (size_t q = 0; q < obs.size(); ++q) {
          const auto &o = obs[q];
          const Eigen::Vector3d v = f.sol.tail<3>();
          const Eigen::Vector2d a(-v.x() + o.x.x() * v.z(), -v.y() + o.x.y() * v.z());
          const Eigen::Vector2d d = o.xdot - flow_rows(o.x, o.rho, o.inv_z) * f.sol;
          const Eigen::Vector2d w = f.w.segment<2>(2 * q);
          num[o.track] += w.dot(a.cwiseProduct(d));
          den[o.track] += w.dot(a.cwiseAbs2());
        }
      }
      for (size_t k = 0; k < n_tracks; ++k)
        eps[k] = den[k] > 0 ? num[k] / den[k] : 0.0;
    }
  };
  std::map<int64_t, FrameFit> fits, fits_psi;
  solve(frames, fits, fits_psi);
  // The focal column: how ω responds to a relative focal error ε, through the whole fit (depth corrections included).
  // A focal error moves a measured point to x_m = x + ε·s(x) (s: focal_dir) and its velocity by ε·J_s·ẋ, and the fit
  // evaluates the model at x_m: to first order the data change by ε·(J_s·F − J_F·s), F the fitted flow at x. The data
  // are perturbed by that for a small ε and fitted again. Only ω's response is used: with ψ's as well, a noise-free
  // 1 % focal error read 0.80 % (without, 1.04 %; docs/diagnose.md).
  const double kappa = 0.01, h = 1e-5;
  FrameMap perturbed = frames;
  for (auto &[t_cam, obs] : perturbed) {
    const FrameFit *fit = fits_psi.count(t_cam) ? &fits_psi.at(t_cam) : fits.count(t_cam) ? &fits.at(t_cam) : nullptr;
    if (!fit)
      continue;
    for (auto &o : obs) {
      const double iz = o.inv_z + eps[o.track];
      const auto F = [&](const Eigen::Vector2d &x) -> Eigen::Vector2d { return flow_rows(x, o.rho, iz) * fit->sol; };
      const Eigen::Vector2d Fx = F(o.x), s = focal_dir(&cam, o.x);
      const Eigen::Vector2d JsF = (focal_dir(&cam, o.x + h * Fx) - focal_dir(&cam, o.x - h * Fx)) / (2 * h);
      const Eigen::Vector2d JFs = (F(o.x + h * s) - F(o.x - h * s)) / (2 * h);
      o.xdot += kappa * (JsF - JFs);
    }
  }
  std::map<int64_t, FrameFit> fits_p, fits_psi_p;
  solve(perturbed, fits_p, fits_psi_p);
  for (auto &[t_cam, f] : fits)
    f.focal = fits_p.count(t_cam) ? ((fits_p.at(t_cam).sol - f.sol) / kappa).eval() : Vec9::Zero();
  const auto body_se = [&](const Eigen::Matrix3d &C) {
    return (R_BC * C * R_BC.transpose()).diagonal().cwiseMax(1e-20).cwiseSqrt().eval();
  };
  // The focal is compared with the gyro put through the images' whole estimator: every feature of an image rotated by
  // the gyro's rotation to each image of its slope window (pure rotation, perspective included), the same slope, the
  // same per-image fit with the same weights. The slope of a quadratic through ±100 ms distorts fast rotation, and
  // the raw gyro made V1_03's oracle run read a 3 % gyro "scale error" and a 0.9 % focal error; the gyro's rotation
  // angle through the slope alone (no perspective) still left 0.46 % (docs/diagnose.md). The time candidates keep the
  // raw gyro: smoothed, it left a −0.5 ms offset on clean runs.
  std::map<std::pair<double, double>, Eigen::Matrix3d> rot_cache;
  const auto R_CjCq = [&](double t0, double t1) -> const Eigen::Matrix3d & {
    auto it = rot_cache.find({t0, t1});
    if (it != rot_cache.end())
      return it->second;
    const double span = 1e-9 * (t1 - t0);
    const int steps = std::max(1, static_cast<int>(std::abs(span) / 1e-3)); // midpoint rule, ~1 ms steps
    const double dt = span / steps;
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity(); // R_{B0 B1}
    for (int k = 0; k < steps; ++k)
      R = R * ov_core::so3_exp(gyro_at(opt.imu, t0 + 1e9 * (k + 0.5) * dt) * dt);
    return rot_cache.emplace(std::make_pair(t0, t1), R_BC.transpose() * R * R_BC).first->second;
  };
  const auto gyro_through_images = [&](int64_t t_cam, const FrameFit &ff) -> Eigen::Vector3d {
    const auto &obs = frames.at(t_cam);
    const Eigen::Index no = static_cast<Eigen::Index>(obs.size());
    const MatrixXd H = frame_design(obs, false);
    VectorXd y(2 * no);
    for (Eigen::Index q = 0; q < no; ++q) {
      const FlowObs &o = obs[q];
      Eigen::Vector2d xdot = Eigen::Vector2d::Zero();
      for (int k = 0; k < o.n_win; ++k) {
        const Eigen::Vector3d b = R_CjCq(o.t_imu, o.win_t_imu[k]).transpose() * o.x.homogeneous();
        xdot += o.win_w[k] * b.head<2>() / b.z();
      }
      y.segment<2>(2 * q) = xdot;
    }
    const MatrixXd Hw = ff.w.asDiagonal() * H;
    return (H.transpose() * Hw).ldlt().solve(Hw.transpose() * y).head<3>();
  };
  for (const auto &[t_cam, ff] : fits) {
    const double t_imu = double(t_cam) + 1e9 * frame_td.at(t_cam);
    FrameRate f;
    f.t = 1e-9 * double(t_cam - t_first);
    f.e = R_BC * ff.sol.head<3>() - gyro_at(opt.imu, t_imu);
    f.gyro_s = R_BC * gyro_through_images(t_cam, ff);
    f.e_s = R_BC * ff.sol.head<3>() - f.gyro_s;
    f.alpha = (gyro_at(opt.imu, t_imu + h_ns) - gyro_at(opt.imu, t_imu - h_ns)) / (2e-9 * h_ns);
    f.se = body_se(ff.C.topLeftCorner<3, 3>());
    f.focal_e = R_BC * ff.focal.head<3>();
    const auto fp = fits_psi.find(t_cam);
    if (fp != fits_psi.end()) {
      f.psi = R_BC * fp->second.sol.segment<3>(3);
      f.psi_se = body_se(fp->second.C.block<3, 3>(3, 3));
    } else { // no ψ row: zero weight
      f.psi.setZero();
      f.psi_se.setConstant(1e30);
    }
    fr.push_back(f);
  }
  if (fr.size() < 50) {
    why = "only " + std::to_string(fr.size()) + " images with 12+ features of known depth";
    return false;
  }
  // Gyro bias per 5-s bin and axis: weighted means removed from the mismatch and the regressors of the ω rows
  // (Frisch-Waugh). The ψ rows carry no gyro bias: α is a difference.
  const int nb = std::max(1, static_cast<int>(std::lround(rep.duration_s / 5.0)));
  const auto bin = [&](double t) {
    return std::min(nb - 1, static_cast<int>(nb * t / std::max(1e-9, rep.duration_s)));
  };
  const double t_mid = 0.5 * rep.duration_s;
  std::vector<Eigen::Vector3d> sw(nb, Eigen::Vector3d::Zero()), se(nb, Eigen::Vector3d::Zero()),
      sa(nb, Eigen::Vector3d::Zero()), sat(nb, Eigen::Vector3d::Zero()), sf(nb, Eigen::Vector3d::Zero()),
      ses(nb, Eigen::Vector3d::Zero()), sgs(nb, Eigen::Vector3d::Zero());
  for (const auto &f : fr) {
    const Eigen::Vector3d w = f.se.cwiseInverse().cwiseAbs2();
    const int b = bin(f.t);
    sw[b] += w, se[b] += w.cwiseProduct(f.e), sa[b] += w.cwiseProduct(f.alpha);
    sat[b] += w.cwiseProduct(f.alpha) * (f.t - t_mid);
    sf[b] += w.cwiseProduct(f.focal_e);
    ses[b] += w.cwiseProduct(f.e_s);
    sgs[b] += w.cwiseProduct(f.gyro_s);
  }
  const Eigen::Index n = kRateRowsPerImage * static_cast<Eigen::Index>(fr.size());
  dr.D = MatrixXd::Zero(n, kNumCols);
  dr.r.resize(n);
  dr.cluster.resize(n);
  dr.t_s.resize(n);
  dr.t_mid = t_mid;
  dr.have_velocity = true;
  dr.have_rate = false;
  Eigen::Index i = 0;
  for (const auto &f : fr) {
    const int b = bin(f.t);
    for (int a = 0; a < 3; ++a, ++i) { // ω rows
      const double sq = 1.0 / f.se(a);
      dr.r(i) = sq * (f.e(a) - se[b](a) / sw[b](a));
      dr.D(i, kV) = sq * (f.alpha(a) - sa[b](a) / sw[b](a));
      dr.D(i, kVt) = sq * (f.alpha(a) * (f.t - t_mid) - sat[b](a) / sw[b](a));
    }
    for (int a = 0; a < 3; ++a, ++i) { // ψ rows
      const double sq = 1.0 / f.psi_se(a);
      dr.r(i) = sq * f.psi(a);
      dr.D(i, kVrow) = sq * f.alpha(a);
    }
    // ω rows against the gyro through the images' estimator, for the scale candidates.
    for (int a = 0; a < 3; ++a, ++i) {
      const double sq = 1.0 / f.se(a);
      dr.r(i) = sq * (f.e_s(a) - ses[b](a) / sw[b](a));
      dr.D(i, kFocal) = sq * (f.focal_e(a) - sf[b](a) / sw[b](a));
      dr.D(i, kGyroScale) = -sq * (f.gyro_s(a) - sgs[b](a) / sw[b](a));
    }
    for (Eigen::Index q = i - kRateRowsPerImage; q < i; ++q) {
      dr.cluster[q] = static_cast<int>(f.t); // one cluster per second: neighbouring images share tracks
      dr.t_s[q] = f.t;
    }
  }
  dr.n_clusters = static_cast<int>(fr.back().t) + 1;
  std::vector<double> absr(n);
  for (Eigen::Index q = 0; q < n; ++q)
    absr[q] = std::abs(dr.r(q));
  dr.scale = std::max(1e-12, 1.4826 * median(absr));
  return true;
}

} // namespace

// ---------------------------------------------------------------------------------------------------------------
// The analysis
// ---------------------------------------------------------------------------------------------------------------

DiagnoseReport diagnose(const ResidualLog &log, const DiagnoseOptions &opt) {
  if (!(opt.min_sigma > 0) || !(opt.min_explained >= 0) || !(opt.huber_k > 0) || opt.time_bins < 1 || opt.plot_bins < 2)
    throw ov_core::UsageError("diagnose: thresholds must be positive and bins at least 1 (time) / 2 (plots)");
  DiagnoseReport rep;
  rep.log_file = log.file;
  rep.options = opt;
  rep.rows_read = static_cast<long>(log.rows.size());

  // Rows with a residual (accepted or gated: a gated feature may be gated precisely because of the missing effect).
  std::vector<const ResidualLogRow *> rows;
  long with_vel = 0;
  for (const auto &r : log.rows) {
    if (r.status == ov_core::ResidualStatus::TriangulationFailed) {
      ++rep.rows_triangulation_failed;
      continue;
    }
    rows.push_back(&r);
    with_vel += r.vel_source != 0;
  }
  // The time candidates need V; keeping rows without it would make their R² not comparable with the others', so the
  // common sample is the rows with a velocity whenever most rows have one (all but the first of each track).
  const bool use_vel =
      !opt.use_logged_velocity || (!rows.empty() && with_vel >= opt.min_velocity_share * double(rows.size()));
  if (use_vel && opt.use_logged_velocity) {
    std::vector<const ResidualLogRow *> kept;
    for (auto *r : rows)
      if (r->vel_source != 0)
        kept.push_back(r);
    rep.rows_without_velocity = static_cast<long>(rows.size() - kept.size());
    rows.swap(kept);
  }
  // Tracks: one feature in one update. Three rows at least: the velocity is a three-point derivative, and the point
  // projection takes three of the 2m residual components.
  const size_t min_track = 3;
  std::map<std::pair<uint64_t, uint64_t>, std::vector<const ResidualLogRow *>> tracks;
  for (auto *r : rows)
    tracks[{r->update_id, r->feature_id}].push_back(r);
  for (auto it = tracks.begin(); it != tracks.end();)
    it = it->second.size() < min_track ? tracks.erase(it) : std::next(it);
  long n_obs = 0;
  for (auto &kv : tracks)
    n_obs += static_cast<long>(kv.second.size());
  if (n_obs < 50)
    throw ov_core::DataError(log.file,
                             "only " + std::to_string(n_obs) +
                                 " usable observations (accepted or gated, in tracks of 3+): too few to diagnose");
  rep.rows_used = n_obs;
  rep.tracks_used = static_cast<long>(tracks.size());

  // Intrinsics: the dataset's camera, given, or fitted from the log (u ≈ cu + fu·x near the centre, where distortion is
  // small).
  if (opt.have_camera) {
    rep.fu = opt.camera.intrinsics(0), rep.fv = opt.camera.intrinsics(1);
    rep.cu = opt.camera.intrinsics(2), rep.cv = opt.camera.intrinsics(3);
  } else if (opt.fu > 0 && opt.fv > 0) {
    rep.fu = opt.fu, rep.fv = opt.fv, rep.cu = opt.cu, rep.cv = opt.cv;
  } else {
    rep.intrinsics_fitted = true;
    for (double rmax : {0.3, 1e9}) {
      Eigen::Matrix2d Au = Eigen::Matrix2d::Zero(), Av = Eigen::Matrix2d::Zero();
      Eigen::Vector2d bu = Eigen::Vector2d::Zero(), bv = Eigen::Vector2d::Zero();
      long cnt = 0;
      for (auto *r : rows) {
        if (r->radius_norm > rmax)
          continue;
        ++cnt;
        const Eigen::Vector2d hu(1, r->x_norm), hv(1, r->y_norm);
        Au += hu * hu.transpose(), bu += hu * r->u_px;
        Av += hv * hv.transpose(), bv += hv * r->v_px;
      }
      if (cnt < 100 && rmax < 1e9)
        continue;
      const Eigen::Vector2d su = Au.ldlt().solve(bu), sv = Av.ldlt().solve(bv);
      rep.cu = su(0), rep.fu = su(1), rep.cv = sv(0), rep.fv = sv(1);
      break;
    }
    if (!(rep.fu > 0) || !(rep.fv > 0))
      throw ov_core::DataError(log.file, "cannot fit the focal length from (u_px, x_norm): pass --dataset");
  }
  double vmax = 0;
  for (auto *r : rows)
    vmax = std::max(vmax, r->v_px);
  rep.image_height = opt.image_height > 0                       ? opt.image_height
                     : opt.have_camera && opt.camera.height > 0 ? opt.camera.height
                                                                : static_cast<int>(std::ceil(vmax + 0.5));
  std::unique_ptr<ov_core::CameraModel> cam;
  if (opt.have_camera)
    cam = std::make_unique<ov_core::CameraModel>(opt.camera);

  // Design matrix.
  Design d;
  const Eigen::Index n = 2 * n_obs;
  d.D = MatrixXd::Zero(n, kNumCols);
  d.r.resize(n);
  d.cluster.resize(n);
  d.t_s.resize(n);
  d.n_clusters = static_cast<int>(tracks.size());
  d.have_velocity = use_vel;
  int64_t t_first = std::numeric_limits<int64_t>::max(), t_last = std::numeric_limits<int64_t>::min();
  for (auto &kv : tracks)
    for (auto *r : kv.second)
      t_first = std::min(t_first, r->t_cam_ns), t_last = std::max(t_last, r->t_cam_ns);
  rep.duration_s = 1e-9 * double(t_last - t_first);
  d.t_mid = 0.5 * rep.duration_s;
  MatrixXd J_point(n, 3); // per track: the point Jacobian (pixels per metre, in the track's first camera frame)
  long rate_rows = 0;
  Eigen::Index i = 0;
  int g = 0;
  for (auto &kv : tracks) {
    auto &tr = kv.second;
    std::sort(tr.begin(), tr.end(), [](auto *a, auto *b) { return a->t_cam_ns < b->t_cam_ns; });
    const size_t m = tr.size();
    bool rates = true, depths = true;
    for (auto *r : tr) {
      rates = rates && r->w_valid;
      depths = depths && std::isfinite(r->depth_m) && r->depth_m > 0;
    }
    // Regressors are built from the filter's PREDICTED observations ẑ = z − r, not from the measured pixels: a
    // measured pixel carries the noise that is also in its residual, and regressing on it fakes effects (an offset of
    // σ²/(Δt·var V) from a velocity, a focal error from a position). ẑ's own error is the triangulated point's
    // J·δp, which the point projection below removes. Velocity: three-point derivative of f·ẑ (exact for a
    // quadratic image track), at every row.
    std::vector<Eigen::Vector2d> xh(m), vel(m, Eigen::Vector2d::Zero());
    std::vector<double> ts(m);
    for (size_t j = 0; j < m; ++j) {
      xh[j] = Eigen::Vector2d(tr[j]->x_norm - tr[j]->res_u_px / rep.fu, tr[j]->y_norm - tr[j]->res_v_px / rep.fv);
      ts[j] = 1e-9 * double(tr[j]->t_cam_ns - t_first);
    }
    for (size_t j = 0; j < m; ++j) {
      if (opt.use_logged_velocity) {
        vel[j] = Eigen::Vector2d(tr[j]->vel_u_px_s, tr[j]->vel_v_px_s);
        continue;
      }
      const size_t a = j == 0 ? 0 : (j + 1 == m ? m - 3 : j - 1); // the three rows around j
      vel[j] = Eigen::Vector2d(rep.fu, rep.fv)
                   .cwiseProduct(lagrange_derivative(ts[a], ts[a + 1], ts[a + 2], xh[a], xh[a + 1], xh[a + 2], ts[j]));
    }
    // Camera rotation along the track (R_C0Cj) from the logged body rates, for the point projection.
    std::vector<Eigen::Matrix3d> R_C0C(m, Eigen::Matrix3d::Identity());
    if (rates && opt.have_camera) {
      const Eigen::Matrix3d R_BC = opt.camera.T_BC.block<3, 3>(0, 0);
      Eigen::Matrix3d R_B0B = Eigen::Matrix3d::Identity();
      for (size_t j = 1; j < m; ++j) {
        const Eigen::Vector3d w0(tr[j - 1]->w_x, tr[j - 1]->w_y, tr[j - 1]->w_z),
            w1(tr[j]->w_x, tr[j]->w_y, tr[j]->w_z);
        R_B0B = R_B0B * ov_core::so3_exp(0.5 * (w0 + w1) * 1e-9 * double(tr[j]->t_cam_ns - tr[j - 1]->t_cam_ns));
        R_C0C[j] = R_BC.transpose() * R_B0B * R_BC;
      }
    }
    Eigen::Vector3d theta = Eigen::Vector3d::Zero(), w_prev = Eigen::Vector3d::Zero();
    int64_t t_prev = tr.front()->t_cam_ns;
    for (size_t j = 0; j < m; ++j) {
      const ResidualLogRow *r = tr[j];
      const double t = ts[j];
      const Eigen::Vector2d V = vel[j];
      const double row_frac = (r->v_px - r->res_v_px) / rep.image_height - 0.5;
      const ErrorDirs dirs = error_dirs(cam.get(), xh[j]);
      const Eigen::Vector3d w(r->w_x, r->w_y, r->w_z);
      if (rates) { // trapezoid integral of the body rate since the track's first row
        theta += 0.5 * (w + w_prev) * 1e-9 * double(r->t_cam_ns - t_prev);
        if (j == 0)
          theta.setZero();
        w_prev = w, t_prev = r->t_cam_ns;
      }
      const double inv_z = depths ? 1.0 / r->depth_m : 1.0;
      const Eigen::Matrix<double, 2, 3> B = rot_flow(xh[j].x(), xh[j].y());
      Eigen::Matrix<double, 2, 3> Jpt;
      Jpt << inv_z, 0.0, -xh[j].x() * inv_z, 0.0, inv_z, -xh[j].y() * inv_z;
      Jpt = Jpt * R_C0C[j].transpose(); // a shift of the point, expressed in the track's first camera frame
      for (int a = 0; a < 2; ++a, ++i) {
        const double fa = a == 0 ? rep.fu : rep.fv;
        d.r(i) = a == 0 ? r->res_u_px : r->res_v_px;
        d.cluster[i] = g;
        d.t_s[i] = t;
        d.D(i, kV) = V(a);
        d.D(i, kVt) = V(a) * (t - d.t_mid);
        d.D(i, kVrow) = V(a) * row_frac;
        d.D(i, kFocal) = fa * dirs.focal(a);
        d.D(i, kPpU) = a == 0 ? 1.0 : 0.0;
        d.D(i, kPpV) = a == 1 ? 1.0 : 0.0;
        d.D(i, kRadial) = fa * dirs.k1(a);
        if (rates)
          for (int c = 0; c < 3; ++c)
            for (int q = 0; q < 3; ++q)
              d.D(i, kGyro0 + 3 * c + q) = fa * B(a, c) * theta(q);
        if (rates && cam) // R_CB known: one isotropic scale, M = −s·R_CB
          d.D(i, kGyroScale) = -fa * B.row(a).dot(opt.camera.T_BC.block<3, 3>(0, 0).transpose() * theta);
        J_point.row(i) = fa * Jpt.row(a);
      }
      rate_rows += rates;
    }
    ++g;
  }
  // Point projection: the filter triangulates each track's point from its observations, so whatever a shift of the
  // point can produce (J_point·δp) is absorbed by it and is not in the residual. Only the part of an effect orthogonal
  // to J_point's columns can show: residual and regressors are projected onto that complement (docs/diagnose.md). A
  // constant image shift lies (nearly) in J_point's span: the principal point column is kept raw and is weak.
  {
    std::vector<int> cols;
    for (int c = 0; c < kNumCols; ++c)
      if (c != kPpU && c != kPpV)
        cols.push_back(c);
    MatrixXd X(n, cols.size() + 1);
    for (size_t c = 0; c < cols.size(); ++c)
      X.col(c) = d.D.col(cols[c]);
    X.col(cols.size()) = d.r;
    project_out_points(J_point, d.cluster, X);
    for (size_t c = 0; c < cols.size(); ++c)
      d.D.col(cols[c]) = X.col(c);
    d.r = X.col(cols.size());
  }
  d.have_rate = rate_rows >= 0.5 * n_obs;
  {
    std::vector<double> absr(n);
    double ss = 0;
    for (Eigen::Index k = 0; k < n; ++k)
      absr[k] = std::abs(d.r(k)), ss += d.r(k) * d.r(k);
    rep.residual_rms_px = std::sqrt(ss / double(n));
    d.scale = std::max(1e-9, 1.4826 * median(absr));
    rep.robust_sigma_px = d.scale;
  }

  // The time candidates: a time-offset error is a per-frame pose change, which a filter whose poses follow the images
  // absorbs (docs/diagnose.md), so with the raw gyro at hand they are tested on the camera's angular rate seen in the
  // images against the gyro's at the filter's image time, not on the residual.
  Design dr;
  const auto defs = candidate_defs();
  std::vector<CandidateResult> res(defs.size());
  for (size_t c = 0; c < defs.size(); ++c)
    res[c].key = defs[c].key, res[c].description = defs[c].description;
  bool rate_time = false;
  std::string rate_why;
  if (!opt.imu.empty() && opt.have_camera) {
    rate_time = build_rate_design(tracks, opt, rep, t_first, dr, rate_why);
  } else {
    rate_why = "no raw gyro (pass --dataset)";
  }
  rep.time_from_rates = rate_time;
  // With rates, the candidates a filter's state absorbs from the residual (time offset, readout, focal) are tested on
  // them; the others stay on the residual.
  static const std::map<std::string, std::string> on_rates = {
      {"td_const", "constant time-offset error, from rates: ω_vis − ω_gyro = α·δt − b"},
      {"td_drift", "drifting time-offset error, from rates: ω_vis − ω_gyro = α·(δt + ḋ·(t − t_mid)) − b"},
      {"rolling_shutter", "rolling-shutter readout, from rates: ψ_vis = α·t_r (rate change from top row to bottom)"},
      {"focal", "focal-length error, from rates: ω_vis − ω̄_gyro = ε·∂ω_vis/∂ε (the whole rate fit's response) − b"},
      {"gyro_scale", "gyro scale error, from rates: ω_vis − ω̄_gyro = −s·ω̄_gyro − b"},
  };
  std::vector<size_t> residual_family, rate_family;
  for (size_t c = 0; c < defs.size(); ++c) {
    const bool rate_capable = on_rates.count(defs[c].key) > 0;
    (rate_capable && rate_time ? rate_family : residual_family).push_back(c);
    if (rate_capable && rate_time)
      res[c].description = on_rates.at(defs[c].key);
    else if (defs[c].key == "td_const" || defs[c].key == "td_drift")
      res[c].note = "on the residual (" + rate_why + "): a lower bound, the poses absorb most of an offset";
    else if (rate_capable)
      res[c].note = "on the residual (" + rate_why + "): a lower bound, the poses absorb most of it";
  }
  // With the camera, R_CB is known and the gyro scale is one number: on rates −ω̄_gyro, on the residual −B·R_CB·Θ.
  std::vector<CandidateDef> used = defs;
  for (size_t c = 0; c < used.size(); ++c)
    if (used[c].key == "gyro_scale" && opt.have_camera) {
      used[c].cols = {kGyroScale};
      used[c].needs_rate = !rate_time;
      if (!rate_time)
        res[c].description = "gyro scale error: r = −s·B(x,y)·R_CB·∫ω dt over the track";
    }
  const auto sel_res = stepwise(d, used, residual_family, opt, rep, res);
  const auto sel_rate = stepwise(dr, used, rate_family, opt, rep, res);
  static const std::map<std::string, std::string> rate_xlabel = {
      {"td_const", "angular acceleration alpha, bias removed, / SE [1/s]"},
      {"td_drift", "fitted alpha * dt(t), bias removed, / SE"},
      {"rolling_shutter", "angular acceleration alpha / SE of psi_vis [1/s]"},
      {"focal", "response of w_vis to a unit focal error, bias removed, / SE"},
      {"gyro_scale", "-w_gyro through the images' estimator, bias removed, / SE [rad/s]"}};
  for (size_t c : rate_family) {
    res[c].curve.xlabel = rate_xlabel.at(defs[c].key);
    res[c].curve.ylabel = "w_vis - w_gyro (bias removed) and psi_vis, / SE (bin mean +- SE)";
  }
  // Ranking: the selected candidates of both families by the share they explain of their own data, then the rest.
  std::vector<size_t> order(sel_res.begin(), sel_res.end());
  order.insert(order.end(), sel_rate.begin(), sel_rate.end());
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return res[a].explained_added > res[b].explained_added; });
  std::vector<size_t> rest;
  for (size_t c = 0; c < defs.size(); ++c)
    if (std::find(order.begin(), order.end(), c) == order.end())
      rest.push_back(c);
  std::stable_sort(rest.begin(), rest.end(), [&](size_t a, size_t b) {
    if ((res[a].sigma > 0) != (res[b].sigma > 0))
      return res[a].sigma > 0;
    if (res[a].explained_added != res[b].explained_added)
      return res[a].explained_added > res[b].explained_added;
    return res[a].explained_alone > res[b].explained_alone;
  });
  order.insert(order.end(), rest.begin(), rest.end());
  for (size_t r = 0; r < order.size(); ++r) {
    res[order[r]].rank = static_cast<int>(r + 1);
    rep.candidates.push_back(res[order[r]]);
  }
  const double k = opt.huber_k;

  // δt per time bin (the trend a drift shows), each bin fitted on its own rows, nothing else removed.
  const Design &dt = rate_time ? dr : d;
  if (dt.have_velocity) {
    const int bins = opt.time_bins;
    const Eigen::Index nt = dt.r.size();
    std::vector<int> bin_of(nt);
    for (Eigen::Index k2 = 0; k2 < nt; ++k2)
      bin_of[k2] = std::min(bins - 1, static_cast<int>(bins * dt.t_s[k2] / std::max(1e-9, rep.duration_s)));
    std::vector<double> td_sum(bins, 0.0);
    std::vector<long> td_cnt(bins, 0);
    for (auto &kv : tracks)
      for (auto *r : kv.second) {
        const int b = std::min(
            bins - 1, static_cast<int>(bins * 1e-9 * double(r->t_cam_ns - t_first) / std::max(1e-9, rep.duration_s)));
        td_sum[b] += r->td_s, ++td_cnt[b];
      }
    for (int b = 0; b < bins; ++b) {
      std::vector<char> mask(nt);
      long cnt = 0;
      for (Eigen::Index k2 = 0; k2 < nt; ++k2)
        cnt += (mask[k2] = bin_of[k2] == b);
      if (cnt < (rate_time ? 5 * kRateRowsPerImage : 40))
        continue;
      const Fit f = fit_cols(dt, {kV}, k, &mask);
      TimeBin tb;
      tb.t_s = (b + 0.5) * rep.duration_s / bins;
      tb.td_ms = 1e3 * f.beta(0);
      tb.td_se_ms = 1e3 * std::sqrt(std::max(0.0, f.cov(0, 0)));
      tb.td_filter_ms = td_cnt[b] ? 1e3 * td_sum[b] / td_cnt[b] : 0.0;
      tb.observations = rate_time ? cnt / kRateRowsPerImage : cnt / 2;
      rep.td_bins.push_back(tb);
    }
  }
  return rep;
}

// ---------------------------------------------------------------------------------------------------------------
// Output
// ---------------------------------------------------------------------------------------------------------------

namespace {

std::string estimates_text(const CandidateResult &c) {
  std::string s;
  for (const auto &e : c.estimates) {
    if (!s.empty())
      s += "; ";
    s += e.name + " " + ov_core::format_fixed(e.value, 3) + " ± " + ov_core::format_fixed(e.stderr_, 3) +
         (e.unit.empty() ? "" : " " + e.unit);
  }
  return s.empty() ? "-" : s;
}

void write_file(const std::string &file, const std::string &text) {
  std::ofstream out(file);
  if (!out)
    throw ov_core::DataError(file, "cannot open for writing");
  out << text;
  out.close();
  if (!out)
    throw ov_core::DataError(file, "write failed");
}

/// The plots' font is ASCII: the few Greek letters and symbols of the model texts spelled out.
std::string ascii_text(const std::string &in) {
  static const std::vector<std::pair<std::string, std::string>> map = {
      {"·", "*"},     {"δ", "d"},    {"ω", "w"},  {"α", "alpha "}, {"ε", "eps"}, {"ḋ", "rate"}, {"−", "-"}, {"±", "+-"},
      {"Θ", "Theta"}, {"∫", "int "}, {"²", "^2"}, {"‖", "|"},      {"—", "-"},   {"√", "sqrt"}, {"t̂", "t^"}};
  std::string s = in;
  for (const auto &[from, to] : map)
    for (size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size()))
      s.replace(p, from.size(), to);
  std::string out;
  for (unsigned char ch : s)
    if (ch < 0x80)
      out += static_cast<char>(ch);
  return out;
}

/// Bin means with ±1 SE bars (vertical segments broken by NaN) and the fitted line.
void plot_curve(const CandidateResult &c, const std::string &file) {
  const BinnedCurve &cu = c.curve;
  PlotOptions po;
  po.title =
      ascii_text("#" + std::to_string(c.rank) + " " + c.key + ": " + c.description.substr(0, c.description.find(':')));
  po.xlabel = cu.xlabel;
  po.ylabel = cu.ylabel;
  Plot p(po);
  std::vector<double> ex, ey;
  for (size_t i = 0; i < cu.x.size(); ++i) {
    ex.insert(ex.end(), {cu.x[i], cu.x[i], std::nan("")});
    ey.insert(ey.end(), {cu.mean[i] - cu.se[i], cu.mean[i] + cu.se[i], std::nan("")});
  }
  Series bars("", ex, ey, Series::Style::Line);
  bars.color = cv::Scalar(60, 60, 60);
  p.add(bars);
  Series pts("bin mean (+-1 SE)", cu.x, cu.mean, Series::Style::Points);
  pts.width = 4;
  p.add(pts);
  p.add_line(cu.slope, cu.intercept, ascii_text("fit: " + estimates_text(c)).substr(0, 70));
  p.save_png(file);
}

void plot_td_bins(const DiagnoseReport &rep, const std::string &file) {
  PlotOptions po;
  po.title = rep.time_from_rates ? "time-offset error per time bin (true - filter's t_d), w_vis - w_gyro = alpha*dt"
                                 : "time-offset error per time bin (true - filter's t_d), from r = V*dt in each bin";
  po.xlabel = "time since first logged row [s]";
  po.ylabel = "offset [ms]";
  Plot p(po);
  std::vector<double> x, y, yt, ex, ey;
  for (const auto &b : rep.td_bins) {
    x.push_back(b.t_s), y.push_back(b.td_ms), yt.push_back(b.td_filter_ms + b.td_ms);
    ex.insert(ex.end(), {b.t_s, b.t_s, std::nan("")});
    ey.insert(ey.end(), {b.td_ms - b.td_se_ms, b.td_ms + b.td_se_ms, std::nan("")});
  }
  Series bars("", ex, ey, Series::Style::Line);
  bars.color = cv::Scalar(60, 60, 60);
  p.add(bars);
  Series pts("offset error dt (+-1 SE)", x, y, Series::Style::Points);
  pts.width = 4;
  p.add(pts);
  p.add(Series("filter t_d + dt (implied true offset)", x, yt, Series::Style::Line));
  for (const auto &c : rep.candidates)
    if (c.key == "td_drift" && c.estimates.size() >= 3)
      p.add_line(c.estimates[0].value, c.estimates[2].value - c.estimates[0].value * 0.5 * rep.duration_s,
                 "td_drift fit: " + ov_core::format_fixed(c.estimates[0].value, 3) + " ms/s");
  p.add_hline(0.0);
  p.save_png(file);
}

} // namespace

std::string format_ranking(const DiagnoseReport &rep) {
  std::ostringstream os;
  os << "rank  candidate         verdict        alone[%]  added[%]   sigma  estimate\n";
  for (const auto &c : rep.candidates) {
    os << std::left << std::setw(6) << c.rank << std::setw(18) << c.key << std::setw(15)
       << (c.explained ? "EXPLAINED" : "not explained") << std::right << std::setw(8)
       << ov_core::format_fixed(100 * c.explained_alone, 2) << std::setw(10)
       << ov_core::format_fixed(100 * c.explained_added, 2) << std::setw(8) << ov_core::format_fixed(c.sigma, 1) << "  "
       << estimates_text(c) << (c.note.empty() ? "" : "  [" + c.note + "]") << "\n";
  }
  return os.str();
}

std::vector<std::string> write_diagnose_report(const DiagnoseReport &rep, const std::string &out_dir) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (!std::filesystem::is_directory(out_dir))
    throw ov_core::DataError(out_dir, "cannot create the output folder");
  std::vector<std::string> files;
  // Plots first, so the report can link them.
  std::vector<std::pair<std::string, std::string>> plots; // key, file name
  int plotted = 0;
  for (const auto &c : rep.candidates) {
    if (plotted >= 3)
      break;
    if (c.curve.x.size() < 2)
      continue;
    const std::string name = "diagnose_" + std::to_string(c.rank) + "_" + c.key + ".png";
    plot_curve(c, ov_core::join_path(out_dir, name));
    plots.push_back({c.key, name});
    files.push_back(ov_core::join_path(out_dir, name));
    ++plotted;
  }
  if (rep.td_bins.size() >= 2) {
    const std::string name = "diagnose_td_per_time_bin.png";
    plot_td_bins(rep, ov_core::join_path(out_dir, name));
    plots.push_back({"td_bins", name});
    files.push_back(ov_core::join_path(out_dir, name));
  }

  const auto &o = rep.options;
  std::ostringstream md;
  md << "# Residual diagnosis\n\n"
     << "Log: `" << rep.log_file << "`\n\n"
     << "- rows read " << rep.rows_read << "; used " << rep.rows_used << " observations in " << rep.tracks_used
     << " tracks (accepted + chi-square gated); " << rep.rows_triangulation_failed << " triangulation-failure rows and "
     << rep.rows_without_velocity << " rows without image velocity left out\n"
     << "- span " << ov_core::format_fixed(rep.duration_s, 1) << " s; residual RMS "
     << ov_core::format_fixed(rep.residual_rms_px, 3) << " px, robust sigma "
     << ov_core::format_fixed(rep.robust_sigma_px, 3) << " px\n"
     << "- intrinsics " << (rep.intrinsics_fitted ? "fitted from the log" : "from the dataset") << ": fu "
     << ov_core::format_fixed(rep.fu, 1) << ", fv " << ov_core::format_fixed(rep.fv, 1) << ", cu "
     << ov_core::format_fixed(rep.cu, 1) << ", cv " << ov_core::format_fixed(rep.cv, 1) << " px; image height "
     << rep.image_height << " px; image velocity "
     << (o.use_logged_velocity ? "from the log's column" : "from the track's predicted positions") << "\n"
     << "- time candidates: "
     << (rep.time_from_rates ? "the images' angular rate against the raw gyro's at the filter's image time"
                             : "on the residual (no raw gyro: pass --dataset); a lower bound")
     << "\n"
     << "- verdict rule: EXPLAINED when selected by forward stepwise regression: significance >= "
     << ov_core::format_fixed(o.min_sigma, 1)
     << " sigma (Wald, track-clustered) and >= " << ov_core::format_fixed(100 * o.min_explained, 1)
     << " % of the Huber loss of its data (the residual; for time candidates from rates, the rate mismatch) removed "
        "beyond the candidates selected before it\n\n";
  const auto first = std::find_if(rep.candidates.begin(), rep.candidates.end(), [](auto &c) { return c.explained; });
  if (first == rep.candidates.end())
    md << "**No candidate explains the residuals** (nothing passes both thresholds).\n\n";
  else
    md << "**Top effect: " << first->key << "** — " << first->description << "; " << estimates_text(*first)
       << "; removes " << ov_core::format_fixed(100 * first->explained_added, 1) << " % of the "
       << (rep.time_from_rates && first->key.rfind("td_", 0) == 0 ? "rate mismatch's" : "residual's") << " loss.\n\n";
  md << "| rank | candidate | verdict | explained alone [%] | added [%] | sigma | estimate (± 1 SE) | note |\n"
     << "|---:|---|---|---:|---:|---:|---|---|\n";
  for (const auto &c : rep.candidates)
    md << "| " << c.rank << " | " << c.key << " | " << (c.explained ? "**explained**" : "not explained") << " | "
       << ov_core::format_fixed(100 * c.explained_alone, 2) << " | "
       << ov_core::format_fixed(100 * c.explained_added, 2) << " | " << ov_core::format_fixed(c.sigma, 1) << " | "
       << estimates_text(c) << " | " << c.note << " |\n";
  md << "\nModels:\n\n";
  for (const auto &c : rep.candidates)
    md << "- `" << c.key << "`: " << c.description << "\n";
  if (!rep.td_bins.empty()) {
    md << "\nTime-offset error per time bin (each bin fitted alone, r = V·δt):\n\n"
       << "| t [s] | δt [ms] | SE [ms] | filter t̂_d [ms] | t̂_d + δt [ms] | observations |\n"
       << "|---:|---:|---:|---:|---:|---:|\n";
    for (const auto &b : rep.td_bins)
      md << "| " << ov_core::format_fixed(b.t_s, 1) << " | " << ov_core::format_fixed(b.td_ms, 3) << " | "
         << ov_core::format_fixed(b.td_se_ms, 3) << " | " << ov_core::format_fixed(b.td_filter_ms, 3) << " | "
         << ov_core::format_fixed(b.td_filter_ms + b.td_ms, 3) << " | " << b.observations << " |\n";
  }
  if (!plots.empty()) {
    md << "\nPlots:\n\n";
    for (const auto &pl : plots)
      md << "![" << pl.first << "](" << pl.second << ")\n";
  }
  md << "\nCaveat: residuals are logged after the filter has absorbed part of any effect into its state (poses, "
        "biases, t̂_d); what the tracks' points absorb is projected out, what the poses absorb is not. Residual-based "
        "sizes are therefore lower bounds (docs/diagnose.md, \"What the residuals cannot show\").\n";
  const std::string md_file = ov_core::join_path(out_dir, "diagnose.md");
  write_file(md_file, md.str());
  files.insert(files.begin(), md_file);

  std::ostringstream js;
  js << "{\n  \"log\": " << ov_core::json_string(rep.log_file) << ",\n  \"rows_read\": " << rep.rows_read
     << ",\n  \"rows_used\": " << rep.rows_used << ",\n  \"tracks_used\": " << rep.tracks_used
     << ",\n  \"rows_triangulation_failed\": " << rep.rows_triangulation_failed
     << ",\n  \"rows_without_velocity\": " << rep.rows_without_velocity
     << ",\n  \"duration_s\": " << ov_core::json_number(rep.duration_s)
     << ",\n  \"residual_rms_px\": " << ov_core::json_number(rep.residual_rms_px)
     << ",\n  \"robust_sigma_px\": " << ov_core::json_number(rep.robust_sigma_px)
     << ",\n  \"intrinsics\": {\"fu\": " << ov_core::json_number(rep.fu) << ", \"fv\": " << ov_core::json_number(rep.fv)
     << ", \"cu\": " << ov_core::json_number(rep.cu) << ", \"cv\": " << ov_core::json_number(rep.cv)
     << ", \"fitted\": " << (rep.intrinsics_fitted ? "true" : "false") << "},\n  \"image_height\": " << rep.image_height
     << ",\n  \"min_sigma\": " << ov_core::json_number(o.min_sigma)
     << ",\n  \"min_explained\": " << ov_core::json_number(o.min_explained)
     << ",\n  \"top\": " << (first == rep.candidates.end() ? "null" : ov_core::json_string(first->key))
     << ",\n  \"candidates\": [";
  for (size_t c = 0; c < rep.candidates.size(); ++c) {
    const auto &cr = rep.candidates[c];
    js << (c ? "," : "") << "\n    {\"rank\": " << cr.rank << ", \"key\": " << ov_core::json_string(cr.key)
       << ", \"model\": " << ov_core::json_string(cr.description)
       << ", \"explained\": " << (cr.explained ? "true" : "false")
       << ", \"explained_alone\": " << ov_core::json_number(cr.explained_alone)
       << ", \"explained_added\": " << ov_core::json_number(cr.explained_added)
       << ", \"sigma\": " << ov_core::json_number(cr.sigma) << ", \"note\": " << ov_core::json_string(cr.note)
       << ", \"estimates\": [";
    for (size_t e = 0; e < cr.estimates.size(); ++e)
      js << (e ? ", " : "") << "{\"name\": " << ov_core::json_string(cr.estimates[e].name)
         << ", \"unit\": " << ov_core::json_string(cr.estimates[e].unit)
         << ", \"value\": " << ov_core::json_number(cr.estimates[e].value)
         << ", \"stderr\": " << ov_core::json_number(cr.estimates[e].stderr_) << "}";
    js << "]}";
  }
  js << "\n  ],\n  \"td_bins\": [";
  for (size_t b = 0; b < rep.td_bins.size(); ++b) {
    const auto &tb = rep.td_bins[b];
    js << (b ? "," : "") << "\n    {\"t_s\": " << ov_core::json_number(tb.t_s)
       << ", \"td_error_ms\": " << ov_core::json_number(tb.td_ms)
       << ", \"td_error_se_ms\": " << ov_core::json_number(tb.td_se_ms)
       << ", \"td_filter_ms\": " << ov_core::json_number(tb.td_filter_ms) << ", \"observations\": " << tb.observations
       << "}";
  }
  js << "\n  ]\n}\n";
  const std::string js_file = ov_core::join_path(out_dir, "diagnose.json");
  write_file(js_file, js.str());
  files.insert(files.begin() + 1, js_file);
  return files;
}

} // namespace ov_eval
