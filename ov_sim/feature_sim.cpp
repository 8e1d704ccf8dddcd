#include "ov_sim/feature_sim.h"
#include "ov_core/types/errors.h"
#include <algorithm>
#include <cmath>

namespace ovton::sim {

FeatureSimulator::FeatureSimulator(const ovton::core::CameraModel &cam, const Scene &scene,
                                   const FeatureSimOptions &opt)
    : cam_(cam), scene_(scene), opt_(opt), rng_(opt.seed) {
  if (opt.max_tracks <= 0 || opt.grid_cols <= 0 || opt.grid_rows <= 0 || !(opt.mean_track_length >= 1.0))
    throw ovton::core::UsageError("feature simulation: max_tracks, grid and mean_track_length must be positive");
  const auto &surfs = scene.surfaces();
  for (size_t s = 0; s < surfs.size(); ++s) {
    if (surfs[s].mips[0].cols <= 2) // box bottoms rest on the floor
      continue;
    const double area = surfs[s].size_u * surfs[s].size_v;
    const int n = static_cast<int>(area * opt.landmarks_per_m2 + 0.5);
    for (int i = 0; i < n; ++i) {
      // One draw per statement (argument order is unspecified): v first, the order gcc used for every folder so far.
      const double v = rng_.uniform(0.0, surfs[s].size_v);
      const double u = rng_.uniform(0.0, surfs[s].size_u);
      landmarks_.push_back(scene.surface_point(static_cast<int>(s), u, v));
    }
  }
  live_.assign(landmarks_.size(), -1);
}

bool FeatureSimulator::visible(size_t lm, const FramePose &pose, Eigen::Vector2d &uv) const {
  Eigen::Matrix3d R_WC = pose.R_WC;
  Eigen::Vector3d p_WC = pose.p_WC;
  const auto project = [&](Eigen::Vector2d &out) {
    return cam_.project(R_WC.transpose() * (landmarks_[lm] - p_WC), out, nullptr, opt_.min_depth_m);
  };
  if (!project(uv))
    return false;
  if (pose.at_row) {
    // Row v is exposed from at_row(v): iterate v -> pose -> projected row until it stands still.
    constexpr int kMaxIter = 20;
    int it = 0;
    for (; it < kMaxIter; ++it) {
      const double row = uv.y();
      pose.at_row(row, R_WC, p_WC);
      if (!project(uv))
        return false;
      if (std::abs(uv.y() - row) < 1e-10)
        break;
    }
    if (it == kMaxIter)
      return false; // no consistent row (far outside any realistic readout): treat as not seen
  }
  if (!cam_.in_image(uv, opt_.border_px))
    return false;
  const Eigen::Vector3d d_W = landmarks_[lm] - p_WC;
  const double dist = d_W.norm();
  RayHit hit;
  // Occluded when another face is hit clearly before the landmark's own face.
  return scene_.raycast(p_WC, d_W / dist, hit) && hit.t > dist - 1e-4 * (1.0 + dist);
}

std::vector<FeatureObservation> FeatureSimulator::step(const Eigen::Matrix3d &R_WC, const Eigen::Vector3d &p_WC,
                                                       int64_t t_cam_ns) {
  FramePose pose;
  pose.R_WC = R_WC;
  pose.p_WC = p_WC;
  return step(pose, t_cam_ns);
}

std::vector<FeatureObservation> FeatureSimulator::step(const FramePose &pose, int64_t t_cam_ns) {
  const int n_cells = opt_.grid_cols * opt_.grid_rows;
  const int per_cell = std::max(1, opt_.max_tracks / n_cells);
  std::vector<int> cell_count(n_cells, 0);
  const auto cell_of = [&](const Eigen::Vector2d &uv) {
    const int cx = std::clamp(static_cast<int>(uv.x() / cam_.width() * opt_.grid_cols), 0, opt_.grid_cols - 1);
    const int cy = std::clamp(static_cast<int>(uv.y() / cam_.height() * opt_.grid_rows), 0, opt_.grid_rows - 1);
    return cy * opt_.grid_cols + cx;
  };
  std::vector<FeatureObservation> out;
  std::vector<std::pair<size_t, Eigen::Vector2d>> keep;
  const double p_drop = 1.0 / opt_.mean_track_length;
  int n_live = 0;
  for (size_t lm = 0; lm < landmarks_.size(); ++lm) {
    if (live_[lm] < 0)
      continue;
    Eigen::Vector2d uv;
    const bool vis = visible(lm, pose, uv);
    const bool drop = rng_.uniform() < p_drop; // drawn for every live track so streams stay aligned
    if (!vis || drop) {
      live_[lm] = -1;
      continue;
    }
    ++cell_count[cell_of(uv)];
    ++n_live;
    keep.emplace_back(lm, uv);
  }
  // Spawn where the image is short of tracks, from a shuffled list of visible untracked landmarks.
  std::vector<std::pair<size_t, Eigen::Vector2d>> cand;
  for (size_t lm = 0; lm < landmarks_.size(); ++lm) {
    Eigen::Vector2d uv;
    if (live_[lm] < 0 && visible(lm, pose, uv))
      cand.emplace_back(lm, uv);
  }
  for (size_t i = cand.size(); i > 1; --i)
    std::swap(cand[i - 1], cand[static_cast<size_t>(rng_.uniform_int(static_cast<int>(i)))]);
  for (const auto &[lm, uv] : cand) {
    if (n_live >= opt_.max_tracks)
      break;
    const int c = cell_of(uv);
    if (cell_count[c] >= per_cell)
      continue;
    ++cell_count[c];
    ++n_live;
    live_[lm] = static_cast<int64_t>(track_landmark_.size());
    track_landmark_.push_back(lm);
    keep.emplace_back(lm, uv);
  }
  for (const auto &[lm, uv] : keep) {
    if (live_[lm] < 0)
      continue;
    FeatureObservation o;
    o.t_cam_ns = t_cam_ns;
    o.feature_id = static_cast<uint64_t>(live_[lm]);
    const double nv = rng_.normal(); // one draw per statement, v first (gcc's order, as above)
    const double nu = rng_.normal();
    o.uv = uv + opt_.pixel_noise * Eigen::Vector2d(nu, nv);
    out.push_back(o);
  }
  std::sort(out.begin(), out.end(),
            [](const FeatureObservation &a, const FeatureObservation &b) { return a.feature_id < b.feature_id; });
  return out;
}

} // namespace ovton::sim
