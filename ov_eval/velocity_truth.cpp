#include "ov_eval/velocity_truth.h"
#include "ov_core/io/text_format.h"
#include "ov_core/types/errors.h"
#include "ov_eval/metrics.h"
#include "ov_eval/truth_camera.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace ovton::eval {

namespace {

/// The truth camera, and the image-plane motion of a world point it sees.
class TruthProjection {
public:
  explicit TruthProjection(const ovton::core::Dataset &d) : cam_(d) {
    const auto &gt = d.groundtruth;
    // Central differences over one ground-truth step: the poses are interpolated linearly between samples.
    h_ns_ = std::max<int64_t>(2500000, (gt.back().t_ns - gt.front().t_ns) / static_cast<int64_t>(gt.size() - 1));
  }
  const TruthCamera &camera() const { return cam_; }
  /// Normalised projection of p_W at IMU time t; false behind the camera or outside the truth.
  bool project(int64_t t, const Eigen::Vector3d &p_W, Eigen::Vector2d &xy) const {
    CameraPose c;
    if (!cam_.at_imu(t, c))
      return false;
    const Eigen::Vector3d p_C = c.R_WC.transpose() * (p_W - c.p_WC);
    if (p_C.z() <= 0)
      return false;
    xy = p_C.head<2>() / p_C.z();
    return true;
  }
  /// d(normalised projection)/dt at camera stamp t_cam.
  bool velocity(int64_t t_cam, const Eigen::Vector3d &p_W, Eigen::Vector2d &v) const {
    const int64_t t = cam_.t_imu(t_cam);
    Eigen::Vector2d a, b;
    if (!project(t - h_ns_, p_W, a) || !project(t + h_ns_, p_W, b))
      return false;
    v = (b - a) / (2e-9 * static_cast<double>(h_ns_));
    return true;
  }

private:
  TruthCamera cam_;
  int64_t h_ns_;
};

/// Least-squares intersection of the observation rays; false when they do not fix a point in front of the cameras.
bool triangulate(const TruthCamera &cam, const std::vector<const ovton::core::VelocityLogRow *> &obs, double min_depth,
                 Eigen::Vector3d &p_W) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  int used = 0;
  for (const auto *o : obs) {
    CameraPose c;
    if (!cam.at_image(o->t_cam_ns, c))
      continue;
    const Eigen::Vector3d d = (c.R_WC * Eigen::Vector3d(o->x_norm, o->y_norm, 1.0)).normalized();
    const Eigen::Matrix3d M = Eigen::Matrix3d::Identity() - d * d.transpose();
    A += M;
    b += M * c.p_WC;
    ++used;
  }
  if (used < 2)
    return false;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(A);
  if (svd.singularValues()(2) < 1e-6 * svd.singularValues()(0))
    return false;
  p_W = A.ldlt().solve(b);
  for (const auto *o : obs) {
    CameraPose c;
    if (cam.at_image(o->t_cam_ns, c) && (c.R_WC.transpose() * (p_W - c.p_WC)).z() < min_depth)
      return false;
  }
  return true;
}

struct Errors {
  std::vector<double> err, speed;
};

void add(std::map<std::pair<std::string, std::string>, Errors> &acc, const std::string &obs, const std::string &rule,
         double vx, double vy, const Eigen::Vector2d &truth_px) {
  if (!std::isfinite(vx) || !std::isfinite(vy))
    return;
  Errors &e = acc[{obs, rule}];
  e.err.push_back((Eigen::Vector2d(vx, vy) - truth_px).norm());
  e.speed.push_back(truth_px.norm());
}

} // namespace

VelocityEvalResult evaluate_velocities(const std::vector<ovton::core::VelocityLogRow> &rows,
                                       const ovton::core::Dataset &data, const VelocityEvalOptions &opt) {
  if (!data.has_groundtruth() || !data.groundtruth.front().has_orientation || data.groundtruth.size() < 2)
    throw ovton::core::UsageError("scoring velocities needs full-pose ground truth in " + data.root);
  const TruthProjection proj(data);
  const TruthCamera &cam = proj.camera();
  VelocityEvalResult r;
  r.rows = static_cast<long>(rows.size());
  std::map<uint64_t, std::vector<const ovton::core::VelocityLogRow *>> tracks;
  for (const auto &row : rows)
    tracks[row.feature_id].push_back(&row);
  r.features = static_cast<long>(tracks.size());
  std::map<std::pair<std::string, std::string>, Errors> acc;
  for (const auto &[id, obs] : tracks) {
    Eigen::Vector3d p_W;
    if (!triangulate(cam, obs, opt.min_depth_m, p_W))
      continue;
    // Reprojection with the true poses: a bad track (a KLT slip, an occlusion edge) has no single true point.
    double sq = 0;
    int n = 0;
    for (const auto *o : obs) {
      Eigen::Vector2d xy;
      if (proj.project(cam.t_imu(o->t_cam_ns), p_W, xy)) {
        sq += (xy - Eigen::Vector2d(o->x_norm, o->y_norm)).squaredNorm() * o->focal_px * o->focal_px;
        ++n;
      }
    }
    if (n < 2 || std::sqrt(sq / n) > opt.max_reproj_px)
      continue;
    ++r.features_scored;
    // eq. 2 velocities of the track's second and third observations: the rule `next` is the first, a quadratic
    // through the first three positions gives V^k ≈ 1.5·V^{k+1} − 0.5·V^{k+2} (constant acceleration).
    std::map<int, const ovton::core::VelocityLogRow *> by_index;
    for (const auto *o : obs)
      by_index[o->obs_index] = o;
    for (const auto *o : obs) {
      Eigen::Vector2d v;
      if (!proj.velocity(o->t_cam_ns, p_W, v))
        continue;
      const Eigen::Vector2d truth = v * o->focal_px;
      const bool first = o->obs_index == 0 && !std::isfinite(o->eq2_x);
      if (first) {
        ++r.first_observations;
        add(acc, "first", "next", o->next_x, o->next_y, truth);
        const auto o2 = by_index.find(o->obs_index + 2);
        if (o2 != by_index.end() && std::isfinite(o->next_x) && std::isfinite(o2->second->eq2_x))
          add(acc, "first", "quadratic", 1.5 * o->next_x - 0.5 * o2->second->eq2_x,
              1.5 * o->next_y - 0.5 * o2->second->eq2_y, truth);
        add(acc, "first", "its_fvon", o->its_x, o->its_y, truth);
        add(acc, "first", "f2f_fvon", o->f2f_x, o->f2f_y, truth);
        // The network Algorithm 1 picked for it, before and after the filter's gate.
        if (o->fvon_source == 2 || o->fvon_source == 3) {
          const bool its = o->fvon_source == 2;
          const double vx = its ? o->its_x : o->f2f_x, vy = its ? o->its_y : o->f2f_y;
          add(acc, "first", "fvon_chosen", vx, vy, truth);
          if (!o->gated)
            add(acc, "first", "fvon_passed_gate", vx, vy, truth);
          ++r.fvon_predictions;
          r.fvon_gated += o->gated;
        }
      } else {
        add(acc, "tracked", "eq2", o->eq2_x, o->eq2_y, truth);
      }
    }
  }
  for (auto &[key, e] : acc) {
    VelocityScore s;
    s.observations = key.first;
    s.rule = key.second;
    s.count = static_cast<long>(e.err.size());
    double sq = 0, sp = 0;
    long in = 0;
    for (size_t k = 0; k < e.err.size(); ++k) {
      sq += e.err[k] * e.err[k];
      sp += e.speed[k] * e.speed[k];
      in += e.err[k] <= opt.gate_px_s;
    }
    s.rms_px_s = std::sqrt(sq / s.count);
    s.true_rms_px_s = std::sqrt(sp / s.count);
    s.within_gate = static_cast<double>(in) / s.count;
    std::nth_element(e.err.begin(), e.err.begin() + e.err.size() / 2, e.err.end());
    s.median_px_s = e.err[e.err.size() / 2];
    r.scores.push_back(s);
  }
  // First observations first, then by rule in a fixed order.
  const auto rank = [](const VelocityScore &s) {
    const char *order[] = {"next", "quadratic", "its_fvon", "f2f_fvon", "fvon_chosen", "fvon_passed_gate", "eq2"};
    int k = 0;
    while (k < 7 && s.rule != order[k])
      ++k;
    return (s.observations == "first" ? 0 : 10) + k;
  };
  std::sort(r.scores.begin(), r.scores.end(), [&](const auto &a, const auto &b) { return rank(a) < rank(b); });
  return r;
}

std::string velocity_table(const VelocityEvalResult &r) {
  std::ostringstream os;
  os << r.features_scored << " of " << r.features << " tracks scored (triangulated from the true poses), "
     << r.first_observations << " first observations; FVON predicted " << r.fvon_predictions << ", of which "
     << r.fvon_gated << " failed the filter's gate.\n\n";
  os << "| observations | velocity | count | RMS error [px/s] | median error [px/s] | within gate | true speed RMS "
        "[px/s] |\n|---|---|---:|---:|---:|---:|---:|\n";
  for (const auto &s : r.scores)
    os << "| " << s.observations << " | " << s.rule << " | " << s.count << " | "
       << ovton::core::format_fixed(s.rms_px_s, 1) << " | " << ovton::core::format_fixed(s.median_px_s, 1) << " | "
       << ovton::core::format_fixed(100.0 * s.within_gate, 1) << " % | "
       << ovton::core::format_fixed(s.true_rms_px_s, 1) << " |\n";
  return os.str();
}

} // namespace ovton::eval
