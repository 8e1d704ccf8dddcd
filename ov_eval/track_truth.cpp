#include "ov_eval/track_truth.h"
#include "ov_core/cam/camera_model.h"
#include "ov_core/io/csv.h"
#include "ov_core/io/text_format.h"
#include "ov_core/types/errors.h"
#include "ov_eval/metrics.h"
#include "ov_eval/truth_camera.h"

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <map>
#include <random>
#include <sstream>

namespace ovton::eval {

namespace {

struct Obs {
  CameraPose cam;
  Eigen::Vector2d uv;
  int age; ///< index in the whole track
};

/// Point minimising the Huber-weighted pixel errors with the camera poses fixed (rays' intersection, then
/// Gauss-Newton). Writes the errors uv − π(p); false when it cannot be fitted in front of every camera.
bool fit_point(const ovton::core::CameraModel &cm, const std::vector<Obs> &obs, const TrackTruthOptions &opt,
               std::vector<Eigen::Vector2d> &err, Eigen::Vector3d *point = nullptr) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const Obs &o : obs) {
    const Eigen::Vector3d d = (o.cam.R_WC * cm.unproject(o.uv)).normalized();
    const Eigen::Matrix3d M = Eigen::Matrix3d::Identity() - d * d.transpose();
    A += M;
    b += M * o.cam.p_WC;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(A);
  if (!(es.eigenvalues()(0) > 1e-9 * es.eigenvalues()(2)))
    return false;
  Eigen::Vector3d p = A.ldlt().solve(b);
  err.resize(obs.size());
  for (int it = 0; it < 15; ++it) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < obs.size(); ++k) {
      const Eigen::Vector3d p_C = obs[k].cam.R_WC.transpose() * (p - obs[k].cam.p_WC);
      Eigen::Vector2d uv;
      Eigen::Matrix<double, 2, 3> J;
      if (p_C.z() < opt.min_depth_m || !cm.project(p_C, uv, &J))
        return false;
      err[k] = obs[k].uv - uv;
      const double e = err[k].norm();
      const double w = e <= opt.huber_px ? 1.0 : opt.huber_px / e;
      const Eigen::Matrix<double, 2, 3> Jw = J * obs[k].cam.R_WC.transpose();
      H += w * Jw.transpose() * Jw;
      g += w * Jw.transpose() * err[k];
    }
    const Eigen::Vector3d dp = H.ldlt().solve(g);
    if (!dp.allFinite())
      return false;
    p += dp;
    if (dp.norm() < 1e-9)
      break;
  }
  for (size_t k = 0; k < obs.size(); ++k) {
    const Eigen::Vector3d p_C = obs[k].cam.R_WC.transpose() * (p - obs[k].cam.p_WC);
    Eigen::Vector2d uv;
    if (p_C.z() < opt.min_depth_m || !cm.project(p_C, uv))
      return false;
    err[k] = obs[k].uv - uv;
  }
  if (point)
    *point = p;
  return true;
}

/// True image velocity [px/s] at each observation: central difference of the fitted point's projections.
void true_velocities(const std::vector<Obs> &obs, const std::vector<Eigen::Vector2d> &err,
                     const std::vector<int64_t> &t_ns, std::vector<Eigen::Vector2d> &vel) {
  const size_t n = obs.size();
  vel.assign(n, Eigen::Vector2d::Zero());
  for (size_t k = 0; k < n; ++k) {
    const size_t a = k == 0 ? 0 : k - 1, b = k + 1 == n ? n - 1 : k + 1;
    if (a == b)
      continue;
    const Eigen::Vector2d ua = obs[a].uv - err[a], ub = obs[b].uv - err[b];
    vel[k] = (ub - ua) / (1e-9 * static_cast<double>(t_ns[b] - t_ns[a]));
  }
}

/// Groups points by id, each track sorted by time.
std::map<uint64_t, std::vector<const TrackPoint *>> group_tracks(const std::vector<TrackPoint> &points) {
  std::map<uint64_t, std::vector<const TrackPoint *>> tracks;
  for (const auto &p : points)
    tracks[p.id].push_back(&p);
  for (auto &[id, obs] : tracks)
    std::sort(obs.begin(), obs.end(), [](const auto *a, const auto *b) { return a->t_cam_ns < b->t_cam_ns; });
  return tracks;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty())
    return 0.0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

} // namespace

std::vector<TrackPoint> read_track_points(const std::string &csv) {
  ovton::core::TextTableReader r(csv, ',');
  std::vector<std::string> f;
  std::vector<TrackPoint> out;
  while (r.next(f)) {
    if (f.size() != 4)
      r.fail("expected 4 columns (timestamp_ns, feature_id, u, v), found " + std::to_string(f.size()));
    TrackPoint p;
    p.t_cam_ns = r.to_int64(f[0], "timestamp");
    const int64_t id = r.to_int64(f[1], "feature id");
    if (id < 0)
      r.fail("negative feature id");
    p.id = static_cast<uint64_t>(id);
    p.uv = Eigen::Vector2d(r.to_double(f[2], "u"), r.to_double(f[3], "v"));
    out.push_back(p);
  }
  return out;
}

TrackTruthResult score_tracks(const std::vector<TrackPoint> &points, const ovton::core::Dataset &data,
                              const TrackTruthOptions &opt) {
  if (!data.has_groundtruth() || !data.groundtruth.front().has_orientation || data.groundtruth.size() < 2)
    throw ovton::core::UsageError("scoring tracks needs full-pose ground truth in " + data.root);
  if (opt.min_obs < 3 || opt.max_segment < opt.min_obs)
    throw ovton::core::UsageError("score_tracks: need 3 <= min_obs <= max_segment");
  const ovton::core::CameraModel cm(data.cam);
  const TruthCamera truth(data);
  TrackTruthResult r;
  r.observations = static_cast<long>(points.size());
  const auto tracks = group_tracks(points);
  r.tracks = static_cast<long>(tracks.size());

  std::vector<double> lens, lens2, abs_u, abs_v, seg_chi05, seg_chi1;
  double sum_sq = 0, sum_dof = 0, sum_sq_in = 0, sum_dof_in = 0, su = 0, sv = 0, squ = 0, sqv = 0;
  double c_num = 0, c_den = 0, chi05 = 0, chi1 = 0, gate05 = 0, gate1 = 0;
  long n_gt[4] = {0, 0, 0, 0};
  double sq_age[4] = {0, 0, 0, 0};
  const double thr[4] = {1, 2, 3, 5};
  double ev = 0, vv = 0;
  std::vector<Obs> seg;
  std::vector<int64_t> seg_t;
  std::vector<Eigen::Vector2d> err, vel;
  for (const auto &[id, obs] : tracks) {
    lens.push_back(static_cast<double>(obs.size()));
    if (obs.size() >= 2)
      lens2.push_back(static_cast<double>(obs.size()));
    if (static_cast<int>(obs.size()) < opt.min_obs) {
      ++r.tracks_short;
      continue;
    }
    bool any = false;
    for (size_t s0 = 0; s0 < obs.size(); s0 += static_cast<size_t>(opt.max_segment)) {
      const size_t s1 = std::min(obs.size(), s0 + static_cast<size_t>(opt.max_segment));
      if (static_cast<int>(s1 - s0) < opt.min_obs)
        continue;
      seg.clear();
      seg_t.clear();
      for (size_t k = s0; k < s1; ++k) {
        Obs o;
        if (!truth.at_image(obs[k]->t_cam_ns, o.cam))
          continue;
        o.uv = obs[k]->uv;
        o.age = static_cast<int>(k);
        seg.push_back(o);
        seg_t.push_back(obs[k]->t_cam_ns);
      }
      if (static_cast<int>(seg.size()) < opt.min_obs || !fit_point(cm, seg, opt, err))
        continue;
      true_velocities(seg, err, seg_t, vel);
      for (size_t k = 0; k < seg.size(); ++k)
        if (err[k].norm() <= 3.0) { // the slope of the bulk, not of the outliers
          ev += err[k].dot(vel[k]);
          vv += vel[k].squaredNorm();
        }
      any = true;
      ++r.segments;
      const double n = static_cast<double>(seg.size());
      double seg_sq = 0;
      int n_out = 0;
      for (size_t k = 0; k < seg.size(); ++k) {
        const Eigen::Vector2d &e = err[k];
        const double en = e.norm();
        seg_sq += e.squaredNorm();
        su += e.x();
        sv += e.y();
        squ += e.x() * e.x();
        sqv += e.y() * e.y();
        abs_u.push_back(std::abs(e.x()));
        abs_v.push_back(std::abs(e.y()));
        for (int j = 0; j < 4; ++j)
          n_gt[j] += en > thr[j];
        if (en > 3.0)
          ++n_out;
        else
          sum_sq_in += e.squaredNorm();
        const int a = seg[k].age < 5 ? 0 : seg[k].age < 10 ? 1 : seg[k].age < 20 ? 2 : 3;
        sq_age[a] += e.squaredNorm();
        ++r.n_age[a];
        if (k > 0) {
          c_num += e.dot(err[k - 1]);
          c_den += 0.5 * (e.squaredNorm() + err[k - 1].squaredNorm());
        }
      }
      r.obs_scored += static_cast<long>(seg.size());
      const double dof = 2 * n - 3;
      sum_sq += seg_sq;
      sum_dof += dof;
      sum_dof_in += std::max(0.0, 2 * (n - n_out) - 3);
      const boost::math::chi_squared_distribution<double> chi(dof);
      const double q95 = boost::math::quantile(chi, 0.95);
      chi05 += seg_sq / 0.25 / dof;
      chi1 += seg_sq / dof;
      gate05 += seg_sq / 0.25 > q95;
      gate1 += seg_sq > q95;
    }
    if (!any)
      ++r.tracks_failed;
  }
  if (!lens.empty()) {
    double s = 0;
    for (double l : lens)
      s += l;
    r.len_mean = s / static_cast<double>(lens.size());
    r.len_median = quantile(lens, 0.5);
    r.len_p90 = quantile(lens, 0.9);
  }
  if (!lens2.empty()) {
    double s = 0;
    for (double l : lens2)
      s += l;
    r.len_mean_ge2 = s / static_cast<double>(lens2.size());
  }
  if (r.obs_scored > 0) {
    const double n = static_cast<double>(r.obs_scored);
    r.sigma_px = std::sqrt(sum_sq / sum_dof);
    r.sigma_inlier_px = sum_dof_in > 0 ? std::sqrt(sum_sq_in / sum_dof_in) : 0.0;
    std::vector<double> all = abs_u;
    all.insert(all.end(), abs_v.begin(), abs_v.end());
    r.mad_sigma_px = 1.4826 * quantile(all, 0.5);
    r.mean_u = su / n;
    r.mean_v = sv / n;
    r.rms_u = std::sqrt(squ / n);
    r.rms_v = std::sqrt(sqv / n);
    r.frac_gt1 = static_cast<double>(n_gt[0]) / n;
    r.frac_gt2 = static_cast<double>(n_gt[1]) / n;
    r.frac_gt3 = static_cast<double>(n_gt[2]) / n;
    r.frac_gt5 = static_cast<double>(n_gt[3]) / n;
    r.lag1_corr = c_den > 0 ? c_num / c_den : 0.0;
    r.vel_slope_ms = vv > 0 ? 1e3 * ev / vv : 0.0;
    const double segs = static_cast<double>(r.segments);
    r.chi2_dof_mean_05 = chi05 / segs;
    r.chi2_dof_mean_1 = chi1 / segs;
    r.gated_05 = gate05 / segs;
    r.gated_1 = gate1 / segs;
    for (int a = 0; a < 4; ++a)
      r.rms_age[a] = r.n_age[a] > 0 ? std::sqrt(sq_age[a] / static_cast<double>(r.n_age[a])) : 0.0;
  }
  return r;
}

std::vector<TrackPoint> rewrite_tracks(const std::vector<TrackPoint> &points, const ovton::core::Dataset &data,
                                       TrackRewrite how, double sigma_px, double rho, uint64_t seed,
                                       const TrackTruthOptions &opt) {
  if (!data.has_groundtruth() || !data.groundtruth.front().has_orientation || data.groundtruth.size() < 2)
    throw ovton::core::UsageError("rewriting tracks needs full-pose ground truth in " + data.root);
  if (!(sigma_px >= 0) || !(rho >= 0 && rho < 1))
    throw ovton::core::UsageError("rewrite_tracks: need sigma_px >= 0 and 0 <= rho < 1");
  const ovton::core::CameraModel cm(data.cam);
  const TruthCamera truth(data);
  const auto tracks = group_tracks(points);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  // Two draws per point, one per statement: as two arguments of one call their order is unspecified (gcc and clang
  // differ). y first: gcc's order, in which the measurements in docs/ were made.
  const auto normal2 = [&] {
    const double y = n01(rng);
    const double x = n01(rng);
    return Eigen::Vector2d(x, y);
  };

  // The tracker's own errors, window-sized segments as score_tracks measures them (Shuffle draws from these).
  std::vector<Eigen::Vector2d> pool;
  std::vector<Obs> seg;
  std::vector<Eigen::Vector2d> err;
  if (how == TrackRewrite::Shuffle) {
    for (const auto &[id, obs] : tracks)
      for (size_t s0 = 0; s0 < obs.size(); s0 += static_cast<size_t>(opt.max_segment)) {
        const size_t s1 = std::min(obs.size(), s0 + static_cast<size_t>(opt.max_segment));
        seg.clear();
        for (size_t k = s0; k < s1; ++k) {
          Obs o;
          if (truth.at_image(obs[k]->t_cam_ns, o.cam)) {
            o.uv = obs[k]->uv;
            seg.push_back(o);
          }
        }
        if (static_cast<int>(seg.size()) >= opt.min_obs && fit_point(cm, seg, opt, err))
          pool.insert(pool.end(), err.begin(), err.end());
      }
    std::shuffle(pool.begin(), pool.end(), rng);
    if (pool.empty())
      throw ovton::core::UsageError("rewrite_tracks: no track could be fitted, nothing to shuffle");
  }
  size_t next = 0;
  std::vector<TrackPoint> out;
  out.reserve(points.size());
  for (const auto &[id, obs] : tracks) {
    if (static_cast<int>(obs.size()) < 2)
      continue;
    seg.clear();
    std::vector<const TrackPoint *> kept;
    for (const TrackPoint *p : obs) {
      Obs o;
      if (truth.at_image(p->t_cam_ns, o.cam)) {
        o.uv = p->uv;
        seg.push_back(o);
        kept.push_back(p);
      }
    }
    if (seg.size() < 2 || !fit_point(cm, seg, opt, err))
      continue;
    Eigen::Vector2d ar = normal2() * sigma_px;
    for (size_t k = 0; k < seg.size(); ++k) {
      TrackPoint q = *kept[k];
      q.uv = seg[k].uv - err[k]; // the exact projection of the track's point
      switch (how) {
      case TrackRewrite::Truth:
        break;
      case TrackRewrite::White:
        q.uv += normal2() * sigma_px;
        break;
      case TrackRewrite::Ar1:
        if (k > 0)
          ar = rho * ar + std::sqrt(1 - rho * rho) * sigma_px * normal2();
        q.uv += ar;
        break;
      case TrackRewrite::Shuffle:
        q.uv += pool[next++ % pool.size()];
        break;
      }
      out.push_back(q);
    }
  }
  std::sort(out.begin(), out.end(), [](const TrackPoint &a, const TrackPoint &b) {
    return a.t_cam_ns != b.t_cam_ns ? a.t_cam_ns < b.t_cam_ns : a.id < b.id;
  });
  return out;
}

std::string track_truth_table(const TrackTruthResult &r) {
  using ovton::core::format_fixed;
  std::ostringstream o;
  const auto pct = [](double x) { return format_fixed(100.0 * x, 1) + " %"; };
  o << "| statistic | value |\n|---|---|\n";
  o << "| tracks / observations | " << r.tracks << " / " << r.observations << " |\n";
  o << "| track length [frames]: mean, median, p90 (all); mean of tracks seen twice or more | "
    << format_fixed(r.len_mean, 1) << ", " << format_fixed(r.len_median, 0) << ", " << format_fixed(r.len_p90, 0)
    << "; " << format_fixed(r.len_mean_ge2, 1) << " |\n";
  o << "| scored: segments (<= window) / observations; tracks too short / not fitted | " << r.segments << " / "
    << r.obs_scored << "; " << r.tracks_short << " / " << r.tracks_failed << " |\n";
  o << "| pixel error sigma [px] (dof-corrected), without errors > 3 px, robust (MAD) | " << format_fixed(r.sigma_px, 3)
    << ", " << format_fixed(r.sigma_inlier_px, 3) << ", " << format_fixed(r.mad_sigma_px, 3) << " |\n";
  o << "| per axis RMS u / v [px]; mean (bias) u / v [px] | " << format_fixed(r.rms_u, 3) << " / "
    << format_fixed(r.rms_v, 3) << "; " << format_fixed(r.mean_u, 3) << " / " << format_fixed(r.mean_v, 3) << " |\n";
  o << "| share of observations off by > 1 / 2 / 3 / 5 px | " << pct(r.frac_gt1) << " / " << pct(r.frac_gt2) << " / "
    << pct(r.frac_gt3) << " / " << pct(r.frac_gt5) << " |\n";
  o << "| correlation of consecutive errors along a segment | " << format_fixed(r.lag1_corr, 3) << " |\n";
  o << "| error along the true image velocity, as a time shift [ms] | " << format_fixed(r.vel_slope_ms, 3) << " |\n";
  o << "| segment chi2/dof mean at sigma 0.5 / 1 px | " << format_fixed(r.chi2_dof_mean_05, 2) << " / "
    << format_fixed(r.chi2_dof_mean_1, 2) << " |\n";
  o << "| segments above the 95 % chi2 gate at sigma 0.5 / 1 px | " << pct(r.gated_05) << " / " << pct(r.gated_1)
    << " |\n";
  o << "| RMS error by age in track 0-4 / 5-9 / 10-19 / 20+ frames [px] | " << format_fixed(r.rms_age[0], 3) << " / "
    << format_fixed(r.rms_age[1], 3) << " / " << format_fixed(r.rms_age[2], 3) << " / " << format_fixed(r.rms_age[3], 3)
    << " |\n";
  return o.str();
}

} // namespace ovton::eval
