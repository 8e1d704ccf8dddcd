#include "ov_core/track/track_stereo.h"
#include "ov_core/types/errors.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_map>

namespace ovton::core {

double epipolar_distance(const Eigen::Matrix3d &R_10, const Eigen::Vector3d &t_10, const Eigen::Vector2d &x0,
                         const Eigen::Vector2d &x1) {
  // x1ᵀ E x0 = 0 with E = [t]× R: the line E x0 in camera 1's normalised plane.
  const Eigen::Vector3d l = t_10.cross(R_10 * x0.homogeneous());
  const double n = std::hypot(l.x(), l.y());
  if (!(n > 0))
    return std::numeric_limits<double>::infinity();
  return std::abs(x1.homogeneous().dot(l)) / n;
}

TrackSecondary::TrackSecondary(const CameraModel &primary, const CameraModel &camera, const TrackKLTOptions &opt)
    : primary_(primary), camera_(camera), opt_(opt), prep_(opt) {
  const Eigen::Matrix4d &T0 = primary.calib().T_BC, &T1 = camera.calib().T_BC;
  R_10_ = T1.topLeftCorner<3, 3>().transpose() * T0.topLeftCorner<3, 3>();
  t_10_ = T1.topLeftCorner<3, 3>().transpose() * (T0.topRightCorner<3, 1>() - T1.topRightCorner<3, 1>());
  if (!(t_10_.norm() > 1e-6))
    throw UsageError("TrackSecondary: the two cameras are at the same place (no baseline for an epipolar check)");
  epi_thresh_ = opt_.ransac_px / std::max(camera_.fu(), camera_.fv());
}

bool TrackSecondary::on_epipolar_line(const Eigen::Vector2d &x0, const cv::Point2f &uv, Eigen::Vector2d &xy) const {
  const float b = static_cast<float>(opt_.border_px);
  if (!(uv.x >= b && uv.y >= b && uv.x <= static_cast<float>(camera_.width() - 1) - b &&
        uv.y <= static_cast<float>(camera_.height() - 1) - b))
    return false;
  xy = camera_.undistort(Eigen::Vector2d(uv.x, uv.y));
  return epipolar_distance(R_10_, t_10_, x0, xy) <= epi_thresh_;
}

const std::vector<TrackedFeature> &TrackSecondary::track(int64_t t_cam_ns, const cv::Mat &gray,
                                                         const TrackKLT &primary) {
  if (gray.empty() || gray.type() != CV_8UC1 || gray.cols != camera_.width() || gray.rows != camera_.height())
    throw UsageError("TrackSecondary: expected an 8-bit single-channel image of " + std::to_string(camera_.width()) +
                     "x" + std::to_string(camera_.height()));
  if (has_prev_ && t_cam_ns <= t_prev_ns_)
    throw UsageError("TrackSecondary: image stamp " + std::to_string(t_cam_ns) + " ns is not after the previous one");
  stats_ = SecondaryTrackStats();
  prep_.equalize(gray, img_);
  prep_.build_pyramid(img_, lk_curr_);
  // Where each of the primary's current features is, by id.
  const std::vector<TrackedFeature> &prim = primary.current();
  std::unordered_map<size_t, size_t> where;
  for (size_t i = 0; i < prim.size(); ++i)
    where.emplace(prim[i].id, i);
  std::vector<Eigen::Vector2d> found_xy(prim.size());
  std::vector<cv::Point2f> found_uv(prim.size());
  std::vector<unsigned char> found(prim.size(), 0);

  // 1. This camera's own tracks over time, for features the primary still has.
  LkParams lk = prep_.lk_params();
  if (has_prev_) {
    std::vector<cv::Point2f> prev, next;
    std::vector<size_t> idx; // primary index of each
    std::vector<Eigen::Vector2d> prev_xy;
    for (size_t i = 0; i < ids_.size(); ++i)
      if (const auto it = where.find(ids_[i]); it != where.end()) {
        prev.push_back(pts_[i]);
        prev_xy.push_back(xy_[i]);
        idx.push_back(it->second);
      }
    stats_.num_temporal = static_cast<int>(prev.size());
    std::vector<unsigned char> status;
    if (!prev.empty())
      lk_flow(lk_prev_, lk_curr_, prev, next, status, lk);
    std::vector<cv::Point2f> a, b;
    std::vector<size_t> kept;
    for (size_t j = 0; j < prev.size(); ++j) {
      Eigen::Vector2d xy;
      if (status[j] && on_epipolar_line(prim[idx[j]].xy, next[j], xy)) {
        a.emplace_back(static_cast<float>(prev_xy[j].x()), static_cast<float>(prev_xy[j].y()));
        b.emplace_back(static_cast<float>(xy.x()), static_cast<float>(xy.y()));
        found_xy[idx[j]] = xy;
        found_uv[idx[j]] = next[j];
        kept.push_back(idx[j]);
      }
    }
    std::vector<unsigned char> inlier(kept.size(), 1);
    if (opt_.use_ransac)
      ransac_fundamental(a, b, epi_thresh_, opt_.ransac_confidence, inlier);
    for (size_t j = 0; j < kept.size(); ++j)
      found[kept[j]] = inlier[j];
    stats_.num_temporal_lost =
        stats_.num_temporal - static_cast<int>(std::count(found.begin(), found.end(), static_cast<unsigned char>(1)));
  }

  // 2. Left-right matching of the primary's features this camera lacks, from the primary's image at this instant.
  std::vector<cv::Point2f> from, to;
  std::vector<size_t> idx;
  for (size_t i = 0; i < prim.size(); ++i)
    if (!found[i]) {
      from.emplace_back(static_cast<float>(prim[i].uv.x()), static_cast<float>(prim[i].uv.y()));
      idx.push_back(i);
    }
  if (!from.empty()) {
    std::vector<unsigned char> status;
    to = from; // the rig's cameras look the same way: start where the point is in the primary image
    lk.use_initial = true;
    lk_flow(primary.last_pyramid(), lk_curr_, from, to, status, lk);
    for (size_t j = 0; j < from.size(); ++j) {
      Eigen::Vector2d xy;
      if (status[j] && on_epipolar_line(prim[idx[j]].xy, to[j], xy)) {
        found[idx[j]] = 1;
        found_xy[idx[j]] = xy;
        found_uv[idx[j]] = to[j];
        ++stats_.num_matched;
      } else {
        ++stats_.num_match_rejected;
      }
    }
  }

  // In the primary's order (older tracks first), so that the filter sees the same order every run.
  ids_.clear();
  pts_.clear();
  xy_.clear();
  out_.clear();
  for (size_t i = 0; i < prim.size(); ++i) {
    if (!found[i])
      continue;
    ids_.push_back(prim[i].id);
    pts_.push_back(found_uv[i]);
    xy_.push_back(found_xy[i]);
    out_.push_back({prim[i].id, Eigen::Vector2d(found_uv[i].x, found_uv[i].y), found_xy[i]});
  }
  stats_.num_features = static_cast<int>(out_.size());
  std::swap(lk_prev_, lk_curr_);
  has_prev_ = true;
  t_prev_ns_ = t_cam_ns;
  return out_;
}

} // namespace ovton::core
