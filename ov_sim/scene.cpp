#include "ov_sim/scene.h"
#include "ov_core/types/errors.h"
#include "ov_sim/random.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

namespace ov_sim {

namespace {

double point_box_distance(const Eigen::Vector3d &p, const AlignedBox &b) {
  const Eigen::Vector3d d = (b.lo - p).cwiseMax(p - b.hi).cwiseMax(Eigen::Vector3d::Zero());
  return d.norm();
}

/// Procedural texture: layers of randomly placed rectangles and discs, one layer per size octave, each added
/// as a +/- offset so that coarse structure survives under fine detail. After mip filtering, whatever the
/// viewing distance, some octave is near the pixel scale and gives KLT sharp corners with 15-95 grey-level contrast.
cv::Mat make_texture(int w, int h, const SceneOptions &opt, Rng &rng) {
  cv::Mat acc(h, w, CV_16S, cv::Scalar(128));
  cv::Mat layer(h, w, CV_16S);
  const double area_texels = static_cast<double>(w) * h;
  const double s_min = opt.feature_min_m / opt.texel_m, s_max = opt.feature_max_m / opt.texel_m;
  const int n_oct = std::max(1, static_cast<int>(std::ceil(std::log(s_max / s_min) / std::log(1.6))));
  for (int o = n_oct - 1; o >= 0; --o) {
    const double s = s_min * std::pow(s_max / s_min, n_oct > 1 ? static_cast<double>(o) / (n_oct - 1) : 0.0);
    const double coverage = 0.3;
    const int count = static_cast<int>(coverage * area_texels / (s * s * 1.5)) + 1;
    const double rel = n_oct > 1 ? static_cast<double>(o) / (n_oct - 1) : 1.0; // 0 finest .. 1 coarsest
    // Coarse octaves get more contrast (as in natural images): KLT's coarse pyramid levels see only them, and
    // with equal contrast per octave new corners locked onto wrong minima under 20-30 px motion.
    const double amp = 15.0 + 80.0 * rel;
    layer.setTo(0);
    for (int i = 0; i < count; ++i) {
      const double cx = rng.uniform(-s, w + s), cy = rng.uniform(-s, h + s);
      const short val = static_cast<short>((rng.uniform() < 0.5 ? -1 : 1) * amp * rng.uniform(0.6, 1.0));
      if (rng.uniform() < 0.75) {
        const double sx = s * rng.uniform(0.6, 1.6), sy = s * rng.uniform(0.6, 1.6);
        cv::rectangle(layer, cv::Point(static_cast<int>(cx - sx / 2), static_cast<int>(cy - sy / 2)),
                      cv::Point(static_cast<int>(cx + sx / 2), static_cast<int>(cy + sy / 2)), cv::Scalar(val),
                      cv::FILLED);
      } else {
        cv::circle(layer, cv::Point(static_cast<int>(cx), static_cast<int>(cy)),
                   std::max(1, static_cast<int>(s * rng.uniform(0.3, 0.7))), cv::Scalar(val), cv::FILLED);
      }
    }
    acc += layer;
  }
  cv::Mat tex;
  acc.convertTo(tex, CV_8U); // saturates
  return tex;
}

} // namespace

Scene Scene::around_path(const std::vector<Eigen::Vector3d> &path, const SceneOptions &opt) {
  if (path.empty())
    throw ov_core::UsageError("scene: empty path");
  Eigen::Vector3d lo = path.front(), hi = path.front();
  for (const auto &p : path) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  AlignedBox room;
  room.lo = lo - Eigen::Vector3d(opt.margin_xy_m, opt.margin_xy_m, opt.margin_below_m);
  room.hi = hi + Eigen::Vector3d(opt.margin_xy_m, opt.margin_xy_m, opt.margin_above_m);
  for (int a = 0; a < 2; ++a) {
    const double grow = opt.min_size_xy_m - (room.hi(a) - room.lo(a));
    if (grow > 0) {
      room.lo(a) -= grow / 2;
      room.hi(a) += grow / 2;
    }
  }
  if (room.hi.z() - room.lo.z() < opt.min_height_m)
    room.hi.z() = room.lo.z() + opt.min_height_m;

  // Boxes stand on the floor wherever they keep their clearance from the path (subsampled for speed).
  std::vector<Eigen::Vector3d> sub;
  const size_t stride = std::max<size_t>(1, path.size() / 2000);
  for (size_t i = 0; i < path.size(); i += stride)
    sub.push_back(path[i]);
  Rng rng(derive_seed(opt.seed, 100));
  std::vector<AlignedBox> boxes;
  const double height = room.hi.z() - room.lo.z();
  for (int attempt = 0; attempt < 400 && static_cast<int>(boxes.size()) < opt.num_boxes; ++attempt) {
    const double sx = rng.uniform(0.4, 1.4), sy = rng.uniform(0.4, 1.4), sz = rng.uniform(0.3, 0.7 * height);
    const double x = rng.uniform(room.lo.x() + 0.05, room.hi.x() - 0.05 - sx);
    const double y = rng.uniform(room.lo.y() + 0.05, room.hi.y() - 0.05 - sy);
    AlignedBox b;
    b.lo = Eigen::Vector3d(x, y, room.lo.z());
    b.hi = Eigen::Vector3d(x + sx, y + sy, room.lo.z() + sz);
    bool ok = true;
    for (const auto &p : sub)
      if (point_box_distance(p, b) < opt.box_clearance_m) {
        ok = false;
        break;
      }
    for (const auto &o : boxes) // keep boxes apart so each shows its faces
      if ((b.lo.head<2>() - o.hi.head<2>()).maxCoeff() < 0.2 && (o.lo.head<2>() - b.hi.head<2>()).maxCoeff() < 0.2)
        ok = false;
    if (ok)
      boxes.push_back(b);
  }
  return Scene(room, boxes, opt);
}

Scene::Scene(const AlignedBox &room, const std::vector<AlignedBox> &boxes, const SceneOptions &opt)
    : room_(room), boxes_(boxes), opt_(opt) {
  if (!(opt.texel_m > 0) || !(opt.feature_min_m > 0) || !(opt.feature_max_m >= opt.feature_min_m))
    throw ov_core::UsageError("scene: texel and feature sizes must be positive and ordered");
  for (int b = -1; b < static_cast<int>(boxes_.size()); ++b) {
    const AlignedBox &box = b < 0 ? room_ : boxes_[b];
    for (int a = 0; a < 3; ++a)
      for (int side = 0; side < 2; ++side)
        add_face(box, a, side == 1, derive_seed(opt.seed, 1000 + surfaces_.size()));
  }
}

void Scene::add_face(const AlignedBox &b, int axis, bool positive, uint64_t seed) {
  Surface s;
  s.axis = axis;
  s.axis_u = (axis + 1) % 3;
  s.axis_v = (axis + 2) % 3;
  s.origin = b.lo;
  if (positive)
    s.origin(axis) = b.hi(axis);
  s.size_u = b.hi(s.axis_u) - b.lo(s.axis_u);
  s.size_v = b.hi(s.axis_v) - b.lo(s.axis_v);
  Rng rng(seed);
  s.shade = static_cast<float>(rng.uniform(0.75, 1.0));
  const int w = std::max(2, static_cast<int>(std::ceil(s.size_u / opt_.texel_m)));
  const int h = std::max(2, static_cast<int>(std::ceil(s.size_v / opt_.texel_m)));
  // Box bottoms rest on the floor and are never seen: keep them tiny.
  const bool hidden = (&b != &room_) && axis == 2 && !positive;
  s.mips.push_back(hidden ? cv::Mat(2, 2, CV_8U, cv::Scalar(128)) : make_texture(w, h, opt_, rng));
  build_mips(s);
  surfaces_.push_back(std::move(s));
}

void Scene::build_mips(Surface &s) {
  s.mips.resize(1);
  while (s.mips.back().cols > 4 && s.mips.back().rows > 4) {
    cv::Mat next;
    cv::pyrDown(s.mips.back(), next);
    s.mips.push_back(next);
  }
}

bool Scene::raycast(const Eigen::Vector3d &o, const Eigen::Vector3d &d, RayHit &hit) const {
  if ((o.array() < room_.lo.array()).any() || (o.array() > room_.hi.array()).any())
    return false;
  double best = std::numeric_limits<double>::infinity();
  int face = -1;
  for (int a = 0; a < 3; ++a) {
    if (d(a) == 0.0)
      continue;
    const double t = ((d(a) > 0 ? room_.hi(a) : room_.lo(a)) - o(a)) / d(a);
    if (t < best) {
      best = t;
      face = face_index(-1, a, d(a) > 0);
    }
  }
  for (size_t b = 0; b < boxes_.size(); ++b) {
    double tn = -std::numeric_limits<double>::infinity(), tf = std::numeric_limits<double>::infinity();
    int an = -1;
    for (int a = 0; a < 3; ++a) {
      if (d(a) == 0.0) {
        if (o(a) < boxes_[b].lo(a) || o(a) > boxes_[b].hi(a))
          tn = std::numeric_limits<double>::infinity();
        continue;
      }
      double t1 = (boxes_[b].lo(a) - o(a)) / d(a), t2 = (boxes_[b].hi(a) - o(a)) / d(a);
      if (t1 > t2)
        std::swap(t1, t2);
      if (t1 > tn) {
        tn = t1;
        an = a;
      }
      tf = std::min(tf, t2);
    }
    if (an >= 0 && tn <= tf && tn > 0 && tn < best) {
      best = tn;
      face = face_index(static_cast<int>(b), an, d(an) < 0);
    }
  }
  if (face < 0)
    return false;
  const Surface &s = surfaces_[face];
  const Eigen::Vector3d p = o + best * d;
  hit.t = best;
  hit.surface = face;
  hit.u = p(s.axis_u) - s.origin(s.axis_u);
  hit.v = p(s.axis_v) - s.origin(s.axis_v);
  return true;
}

Eigen::Vector3d Scene::surface_point(int surface, double u, double v) const {
  const Surface &s = surfaces_.at(surface);
  Eigen::Vector3d p = s.origin;
  p(s.axis_u) += u;
  p(s.axis_v) += v;
  return p;
}

Eigen::Vector3d Scene::plant_marker(int surface, double u, double v, double radius_m) {
  Surface &s = surfaces_.at(surface);
  const int shift = 8; // sub-texel centre, so the marker sits exactly where asked
  const double x = u / opt_.texel_m - 0.5, y = v / opt_.texel_m - 0.5;
  const cv::Point c(static_cast<int>(std::lround(x * (1 << shift))), static_cast<int>(std::lround(y * (1 << shift))));
  const auto r = [&](double m) { return static_cast<int>(std::lround(m / opt_.texel_m * (1 << shift))); };
  cv::circle(s.mips[0], c, r(2.0 * radius_m), cv::Scalar(255), cv::FILLED, cv::LINE_AA, shift);
  cv::circle(s.mips[0], c, r(radius_m), cv::Scalar(0), cv::FILLED, cv::LINE_AA, shift);
  build_mips(s);
  return surface_point(surface, u, v);
}

} // namespace ov_sim
