#include "ov_core/track/track_klt.h"
#include "ov_core/track/lk_flow.h"
#include "ov_core/types/errors.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

namespace ovton::core {

namespace {

using Clock = std::chrono::steady_clock;

/// Per-thread scratch so that the free function allocates nothing once warmed up.
std::vector<unsigned char> &scratch_mask() {
  thread_local std::vector<unsigned char> m;
  return m;
}

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

void check_option(bool ok, const std::string &what) {
  if (!ok)
    throw UsageError("TrackKLTOptions: " + what);
}

} // namespace

void TrackStatsTotals::add(const TrackStats &s) {
  ++frames;
  t_equalize_ms += s.t_equalize_ms;
  t_pyramid_ms += s.t_pyramid_ms;
  t_tracking_ms += s.t_tracking_ms;
  t_undistort_ms += s.t_undistort_ms;
  t_ransac_ms += s.t_ransac_ms;
  t_detection_ms += s.t_detection_ms;
  t_total_ms += s.t_total_ms;
}

int ransac_fundamental(const std::vector<cv::Point2f> &xy0, const std::vector<cv::Point2f> &xy1, double thresh_norm,
                       double confidence, std::vector<unsigned char> &inlier) {
  if (xy0.size() != xy1.size())
    throw UsageError("ransac_fundamental: point sets differ in size");
  const int n = static_cast<int>(xy0.size());
  inlier.assign(n, 1);
  if (n < 8)
    return n;
  const cv::Mat F = cv::findFundamentalMat(xy0, xy1, cv::FM_RANSAC, thresh_norm, confidence, inlier);
  // No model (degenerate configuration): rejecting everything would end every track on one bad frame.
  if (F.rows != 3 || F.cols != 3 || static_cast<int>(inlier.size()) != n) {
    inlier.assign(n, 1);
    return n;
  }
  const int n_ransac = static_cast<int>(std::count(inlier.begin(), inlier.end(), 1));
  // OpenCV's mask comes from the best minimal (7-point) sample, whose epipolar lines can be off by pixels at the
  // image edges; the returned F is refitted on all inliers, so classify again against it (distance in both views).
  const cv::Matx33d Fm(F);
  const double thresh2 = thresh_norm * thresh_norm;
  int n_refit = 0;
  std::vector<unsigned char> &refit = scratch_mask();
  refit.resize(n);
  for (int i = 0; i < n; ++i) {
    const cv::Vec3d a(xy0[i].x, xy0[i].y, 1.0), b(xy1[i].x, xy1[i].y, 1.0);
    const cv::Vec3d l1 = Fm * a, l0 = Fm.t() * b;
    const double e = b.dot(l1);
    const double d1 = e * e / (l1[0] * l1[0] + l1[1] * l1[1]), d0 = e * e / (l0[0] * l0[0] + l0[1] * l0[1]);
    refit[i] = std::max(d0, d1) <= thresh2;
    n_refit += refit[i];
  }
  // A refit that lost most of the consensus was pulled off by a degenerate inlier set (no parallax): keep RANSAC's.
  if (2 * n_refit < n_ransac)
    return n_ransac;
  inlier.swap(refit);
  return n_refit;
}

LkImagePreparer::LkImagePreparer(const TrackKLTOptions &opt) : opt_(opt) {
  if (opt_.equalization == ImageEqualization::Clahe) {
    check_option(opt_.clahe_clip > 0 && opt_.clahe_tiles > 0, "clahe_clip and clahe_tiles must be positive");
    clahe_ = cv::createCLAHE(opt_.clahe_clip, cv::Size(opt_.clahe_tiles, opt_.clahe_tiles));
  }
}

void LkImagePreparer::equalize(const cv::Mat &gray, cv::Mat &img) const {
  switch (opt_.equalization) {
  case ImageEqualization::None:
    gray.copyTo(img);
    break;
  case ImageEqualization::Histogram:
    cv::equalizeHist(gray, img);
    break;
  case ImageEqualization::Clahe:
    clahe_->apply(gray, img);
    break;
  }
}

void LkImagePreparer::build_pyramid(const cv::Mat &img, LkPyramid &out) {
  cv::buildOpticalFlowPyramid(img, pyr_, cv::Size(opt_.win_size, opt_.win_size), opt_.pyr_levels, false);
  out.build(pyr_, opt_.win_size);
}

LkParams LkImagePreparer::lk_params() const {
  LkParams lk;
  lk.win = opt_.win_size;
  lk.max_level = opt_.pyr_levels;
  lk.max_iter = opt_.lk_max_iter;
  lk.eps = opt_.lk_eps;
  return lk;
}

TrackKLT::TrackKLT(const CameraModel &camera, const TrackKLTOptions &opt) : camera_(camera), opt_(opt), prep_(opt) {
  check_option(opt_.num_features > 0, "num_features must be positive");
  check_option(opt_.grid_x > 0 && opt_.grid_y > 0, "grid_x and grid_y must be positive");
  check_option(opt_.grid_x <= camera_.width() && opt_.grid_y <= camera_.height(), "grid finer than the image");
  check_option(opt_.min_px_dist >= 1, "min_px_dist must be at least 1");
  check_option(opt_.fast_threshold > 0 && opt_.fast_threshold < 255, "fast_threshold must be in (0, 255)");
  check_option(opt_.detect_below_fraction > 0 && opt_.detect_below_fraction <= 1,
               "detect_below_fraction must be in (0, 1]");
  check_option(opt_.border_px >= 0, "border_px must not be negative");
  check_option(opt_.win_size >= 5 && opt_.win_size % 2 == 1, "win_size must be odd and at least 5");
  check_option(opt_.pyr_levels >= 0 && opt_.pyr_levels <= 8, "pyr_levels must be in [0, 8]");
  check_option(opt_.lk_max_iter > 0 && opt_.lk_eps > 0, "lk_max_iter and lk_eps must be positive");
  check_option(opt_.fb_max_px > 0, "fb_max_px must be positive");
  check_option(opt_.ransac_px > 0, "ransac_px must be positive");
  check_option(opt_.ransac_confidence > 0 && opt_.ransac_confidence < 1, "ransac_confidence must be in (0, 1)");
  const size_t cap = static_cast<size_t>(2 * opt_.num_features);
  for (auto *v : {&pts_, &pts_next_, &pts_back_, &xy0f_, &xy1f_})
    v->reserve(cap);
  ids_.reserve(cap);
  xy_.reserve(cap);
  xy_next_.reserve(cap);
  out_.reserve(cap);
  cell_count_.resize(static_cast<size_t>(opt_.grid_x * opt_.grid_y));
}

void TrackKLT::reset() {
  has_prev_ = false;
  ids_.clear();
  pts_.clear();
  xy_.clear();
  out_.clear();
}

const std::vector<TrackedFeature> &TrackKLT::track(int64_t t_cam_ns, const cv::Mat &gray) {
  if (gray.empty() || gray.type() != CV_8UC1)
    throw UsageError("TrackKLT: expected a non-empty 8-bit single-channel image");
  if (gray.cols != camera_.width() || gray.rows != camera_.height())
    throw UsageError("TrackKLT: image is " + std::to_string(gray.cols) + "x" + std::to_string(gray.rows) +
                     " but the camera calibration says " + std::to_string(camera_.width()) + "x" +
                     std::to_string(camera_.height()));
  if (has_prev_ && t_cam_ns <= t_prev_ns_)
    throw UsageError("TrackKLT: image stamp " + std::to_string(t_cam_ns) + " ns is not after the previous one (" +
                     std::to_string(t_prev_ns_) + " ns)");

  stats_ = TrackStats();
  const auto t_start = Clock::now();

  auto t0 = Clock::now();
  // A copy even without equalisation: the caller may reuse its buffer, and last_image() must outlive this call.
  prep_.equalize(gray, img_);
  stats_.t_equalize_ms = ms_since(t0);

  // Built once per image (and copied to float planes for lk_flow): this frame's pyramid becomes the next frame's
  // "previous" one.
  t0 = Clock::now();
  prep_.build_pyramid(img_, lk_curr_);
  stats_.t_pyramid_ms = ms_since(t0);

  stats_.num_prev = static_cast<int>(ids_.size());
  if (has_prev_ && !ids_.empty())
    track_previous(t_cam_ns);
  merge_and_detect();

  out_.resize(ids_.size());
  for (size_t i = 0; i < ids_.size(); ++i) {
    out_[i].id = ids_[i];
    out_[i].uv = Eigen::Vector2d(pts_[i].x, pts_[i].y);
    out_[i].xy = xy_[i];
  }
  stats_.num_features = static_cast<int>(out_.size());

  std::swap(lk_prev_, lk_curr_);
  has_prev_ = true;
  t_prev_ns_ = t_cam_ns;
  stats_.t_total_ms = ms_since(t_start);
  totals_.add(stats_);
  return out_;
}

void TrackKLT::track_previous(int64_t t_cam_ns) {
  const size_t n = ids_.size();
  LkParams lk = prep_.lk_params();

  auto t0 = Clock::now();
  if (opt_.gyro_prior && prior_)
    if (const auto R = prior_->camera_rotation(t_prev_ns_, t_cam_ns)) {
      // A point's undistorted bearing turned by the camera's rotation; one that leaves the image or turns behind
      // the camera starts where it was.
      pts_next_.resize(n);
      for (size_t i = 0; i < n; ++i) {
        const Eigen::Vector3d b = *R * xy_[i].homogeneous();
        const Eigen::Vector2d uv = b.z() > 0.1 ? camera_.distort(b.head<2>() / b.z()) : Eigen::Vector2d(-1, -1);
        const bool inside =
            uv.allFinite() && uv.x() >= 0 && uv.y() >= 0 && uv.x() < camera_.width() && uv.y() < camera_.height();
        pts_next_[i] = inside ? cv::Point2f(static_cast<float>(uv.x()), static_cast<float>(uv.y())) : pts_[i];
      }
      lk.use_initial = true;
    }
  lk_flow(lk_prev_, lk_curr_, pts_, pts_next_, status_, lk);
  keep_.assign(n, 1);
  // Tracks are dropped, not only detections avoided, within border_px of the edge: there the LK window hangs
  // outside the image and the solution drifts (measured: a point walked from v = 12 to v = 0.7 px over eight frames,
  // passed the chi-square gate at 0.5 px noise and pulled the accelerometer bias by 2 m/s²).
  const float b = static_cast<float>(opt_.border_px);
  const float min_x = b, min_y = b;
  const float max_x = static_cast<float>(camera_.width() - 1) - b, max_y = static_cast<float>(camera_.height() - 1) - b;
  for (size_t i = 0; i < n; ++i) {
    const cv::Point2f &p = pts_next_[i];
    if (!status_[i] || !(p.x >= min_x && p.y >= min_y && p.x <= max_x && p.y <= max_y)) {
      keep_[i] = 0;
      ++stats_.num_lk_lost;
    }
  }
  if (opt_.forward_backward) {
    // Track back from where the points landed, starting at their origin; a good track returns to it.
    pts_back_ = pts_;
    lk.use_initial = true;
    lk_flow(lk_curr_, lk_prev_, pts_next_, pts_back_, status_back_, lk);
    const double max2 = opt_.fb_max_px * opt_.fb_max_px;
    for (size_t i = 0; i < n; ++i) {
      if (!keep_[i])
        continue;
      const cv::Point2f d = pts_back_[i] - pts_[i];
      if (!status_back_[i] || d.x * d.x + d.y * d.y > max2) {
        keep_[i] = 0;
        ++stats_.num_fb_rejected;
      }
    }
  }
  stats_.t_tracking_ms = ms_since(t0);

  t0 = Clock::now();
  xy_next_.resize(n);
  for (size_t i = 0; i < n; ++i)
    if (keep_[i])
      xy_next_[i] = camera_.undistort(Eigen::Vector2d(pts_next_[i].x, pts_next_[i].y));
  stats_.t_undistort_ms = ms_since(t0);

  if (opt_.use_ransac) {
    t0 = Clock::now();
    xy0f_.clear();
    xy1f_.clear();
    for (size_t i = 0; i < n; ++i) {
      if (!keep_[i])
        continue;
      xy0f_.emplace_back(static_cast<float>(xy_[i].x()), static_cast<float>(xy_[i].y()));
      xy1f_.emplace_back(static_cast<float>(xy_next_[i].x()), static_cast<float>(xy_next_[i].y()));
    }
    // The threshold is set in pixels, where image noise lives; RANSAC runs in normalised units.
    const double thresh = opt_.ransac_px / std::max(camera_.fu(), camera_.fv());
    ransac_fundamental(xy0f_, xy1f_, thresh, opt_.ransac_confidence, status_back_);
    size_t j = 0;
    for (size_t i = 0; i < n; ++i) {
      if (!keep_[i])
        continue;
      if (!status_back_[j++]) {
        keep_[i] = 0;
        ++stats_.num_ransac_rejected;
      }
    }
    stats_.t_ransac_ms = ms_since(t0);
  }

  pts_.swap(pts_next_);
  xy_.swap(xy_next_);
  compact(keep_);
}

void TrackKLT::compact(const std::vector<unsigned char> &keep) {
  size_t j = 0;
  for (size_t i = 0; i < ids_.size(); ++i) {
    if (!keep[i])
      continue;
    ids_[j] = ids_[i];
    pts_[j] = pts_[i];
    xy_[j] = xy_[i];
    ++j;
  }
  ids_.resize(j);
  pts_.resize(j);
  xy_.resize(j);
}

void TrackKLT::merge_and_detect() {
  const auto t0 = Clock::now();
  const int w = camera_.width(), h = camera_.height();

  // Tracks that converged onto the same spot measure the same point twice and would be fused as independent
  // measurements; keep the older one (lower index = older id), as OpenVINS does, on a grid of half the spacing.
  const int merge_cell = std::max(1, opt_.min_px_dist / 2);
  grid_occ_.create(h / merge_cell + 1, w / merge_cell + 1, CV_8UC1);
  grid_occ_.setTo(0);
  keep_.assign(ids_.size(), 1);
  bool merged = false;
  for (size_t i = 0; i < ids_.size(); ++i) {
    unsigned char &occ =
        grid_occ_.at<unsigned char>(static_cast<int>(pts_[i].y) / merge_cell, static_cast<int>(pts_[i].x) / merge_cell);
    if (occ) {
      keep_[i] = 0;
      merged = true;
      ++stats_.num_merged;
    }
    occ = 1;
  }
  if (merged)
    compact(keep_);

  if (static_cast<double>(ids_.size()) >= opt_.detect_below_fraction * opt_.num_features) {
    stats_.t_detection_ms = ms_since(t0);
    return;
  }

  // Occupancy at full resolution: exact minimum distance to every existing and newly accepted feature.
  mask_.create(h, w, CV_8UC1);
  mask_.setTo(0);
  const int ncells = opt_.grid_x * opt_.grid_y;
  std::fill(cell_count_.begin(), cell_count_.end(), 0);
  auto cell_of = [&](float x, float y) {
    const int cx = std::min(opt_.grid_x - 1, static_cast<int>(x * opt_.grid_x / w));
    const int cy = std::min(opt_.grid_y - 1, static_cast<int>(y * opt_.grid_y / h));
    return cy * opt_.grid_x + cx;
  };
  for (const cv::Point2f &p : pts_) {
    cv::circle(mask_, cv::Point(cvRound(p.x), cvRound(p.y)), opt_.min_px_dist, cv::Scalar(255), cv::FILLED);
    ++cell_count_[cell_of(p.x, p.y)];
  }

  const int quota = (opt_.num_features + ncells - 1) / ncells;
  // FAST only in cells that lack features; the ROI is widened by the FAST radius (3 px) so that corners on cell
  // edges are not lost, and candidates are attributed to the cell that holds them.
  keypoints_.clear();
  for (int cy = 0; cy < opt_.grid_y; ++cy) {
    for (int cx = 0; cx < opt_.grid_x; ++cx) {
      const int c = cy * opt_.grid_x + cx;
      if (cell_count_[c] >= quota)
        continue;
      const int x0 = cx * w / opt_.grid_x, x1 = (cx + 1) * w / opt_.grid_x;
      const int y0 = cy * h / opt_.grid_y, y1 = (cy + 1) * h / opt_.grid_y;
      const cv::Rect roi = cv::Rect(x0 - 3, y0 - 3, x1 - x0 + 6, y1 - y0 + 6) & cv::Rect(0, 0, w, h);
      cv::FAST(img_(roi), cell_kp_, opt_.fast_threshold, true);
      for (cv::KeyPoint kp : cell_kp_) {
        kp.pt.x += static_cast<float>(roi.x);
        kp.pt.y += static_cast<float>(roi.y);
        if (kp.pt.x < x0 || kp.pt.x >= x1 || kp.pt.y < y0 || kp.pt.y >= y1)
          continue;
        if (kp.pt.x < opt_.border_px || kp.pt.y < opt_.border_px || kp.pt.x >= w - opt_.border_px ||
            kp.pt.y >= h - opt_.border_px)
          continue;
        kp.class_id = c;
        keypoints_.push_back(kp);
      }
    }
  }
  std::sort(keypoints_.begin(), keypoints_.end(),
            [](const cv::KeyPoint &a, const cv::KeyPoint &b) { return a.response > b.response; });

  // Pass 1 spreads features with an equal quota per cell. Pass 2 lets textured cells take up to twice the quota
  // when textureless cells could not fill theirs, so the total still approaches the target.
  const size_t target = static_cast<size_t>(opt_.num_features);
  for (int pass = 0; pass < 2 && ids_.size() < target; ++pass) {
    const int cap = pass == 0 ? quota : 2 * quota;
    for (const cv::KeyPoint &kp : keypoints_) {
      if (ids_.size() >= target)
        break;
      if (cell_count_[kp.class_id] >= cap)
        continue;
      const cv::Point ip(cvRound(kp.pt.x), cvRound(kp.pt.y));
      if (mask_.at<unsigned char>(ip.y, ip.x))
        continue;
      cv::circle(mask_, ip, opt_.min_px_dist, cv::Scalar(255), cv::FILLED);
      ++cell_count_[kp.class_id];
      ids_.push_back(next_id_++);
      pts_.push_back(kp.pt);
      xy_.push_back(camera_.undistort(Eigen::Vector2d(kp.pt.x, kp.pt.y)));
      ++stats_.num_detected;
    }
  }
  stats_.t_detection_ms = ms_since(t0);
}

} // namespace ovton::core
