#include "ov_sim/scene.h"
#include "ov_core/types/errors.h"
#include "ov_sim/random.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

namespace ovton::sim {

namespace {

double point_box_distance(const Eigen::Vector3d &p, const AlignedBox &b) {
  const Eigen::Vector3d d = (b.lo - p).cwiseMax(p - b.hi).cwiseMax(Eigen::Vector3d::Zero());
  return d.norm();
}

/// Lit textures keep headroom below 255 for the brighter spots (illumination is 1 on average, up to ~2 under a lamp).
constexpr double kLitScale = 0.7;

} // namespace

Scene Scene::around_path(const std::vector<Eigen::Vector3d> &path, const SceneOptions &opt) {
  if (path.empty())
    throw ovton::core::UsageError("scene: empty path");
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
  const TextureOptions &t = opt.texture;
  if (!(t.texel_m > 0) || !(t.feature_min_m > 0) || !(t.feature_max_m >= t.feature_min_m))
    throw ovton::core::UsageError("scene: texel and feature sizes must be positive and ordered");
  if (!(t.density >= 0 && t.density <= 1) || !(t.grain >= 0) || !(t.weave >= 0) || !(t.stain >= 0 && t.stain < 1) ||
      !(opt.light_ambient > 0 && opt.light_ambient <= 1))
    throw ovton::core::UsageError("scene: texture density in [0, 1], grain >= 0, stain in [0, 1), ambient in (0, 1]");
  if (t.style == TextureStyle::Room)
    place_lamps();
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
  const int w = std::max(2, static_cast<int>(std::ceil(s.size_u / opt_.texture.texel_m)));
  const int h = std::max(2, static_cast<int>(std::ceil(s.size_v / opt_.texture.texel_m)));
  // Box bottoms rest on the floor and are never seen: keep them tiny.
  const bool hidden = (&b != &room_) && axis == 2 && !positive;
  if (hidden)
    s.mips.push_back(cv::Mat(2, 2, CV_8U, cv::Scalar(128)));
  else if (opt_.texture.style == TextureStyle::Blotches)
    s.mips.push_back(make_blotch_texture(w, h, opt_.texture, rng));
  else
    s.mips.push_back(make_room_texture(w, h, face_kind(b, axis, positive), opt_.texture, rng));
  if (!lamps_.empty() && !hidden) {
    // The face's normal towards the viewer: room faces look inwards, box faces outwards.
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    const bool inward = &b == &room_;
    n(axis) = (positive != inward) ? 1.0 : -1.0;
    bake_lighting(s, n);
  }
  build_mips(s);
  surfaces_.push_back(std::move(s));
}

FaceKind Scene::face_kind(const AlignedBox &b, int axis, bool positive) const {
  if (&b != &room_)
    return FaceKind::Object;
  if (axis == 2)
    return positive ? FaceKind::Ceiling : FaceKind::Floor;
  return FaceKind::Wall;
}

void Scene::place_lamps() {
  Rng rng(derive_seed(opt_.seed, 200));
  const Eigen::Vector3d size = room_.hi - room_.lo;
  const int n = std::clamp(static_cast<int>(std::lround(size.x() * size.y() / 10.0)), 2, 12);
  for (int i = 0; i < n; ++i) {
    Lamp l;
    // One draw per statement: the order of a call's arguments is unspecified, so two draws as arguments gave other
    // scenes under clang than under gcc. y is drawn first: gcc's order, in which every rendered folder so far was made.
    const double y = rng.uniform(room_.lo.y() + 0.5, room_.hi.y() - 0.5);
    const double x = rng.uniform(room_.lo.x() + 0.5, room_.hi.x() - 0.5);
    l.position = Eigen::Vector3d(x, y, room_.hi.z() - 0.01);
    lamps_.push_back(l);
  }
  // The lamps' gain makes the mean illumination over floor and walls 1 (sampled on a coarse grid).
  lamp_gain_ = 1.0;
  double sum = 0.0;
  int count = 0;
  for (int a = 0; a < 3; ++a)
    for (int side = 0; side < 2; ++side) {
      if (a == 2 && side == 1)
        continue; // the ceiling is lit by the ambient share only
      const int au = (a + 1) % 3, av = (a + 2) % 3;
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      n(a) = side ? -1.0 : 1.0; // room faces look inwards
      for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j) {
          Eigen::Vector3d p = room_.lo;
          p(a) = side ? room_.hi(a) : room_.lo(a);
          p(au) += (i + 0.5) / 10.0 * size(au);
          p(av) += (j + 0.5) / 10.0 * size(av);
          sum += (illumination(p, n) - opt_.light_ambient);
          ++count;
        }
    }
  lamp_gain_ = sum > 0 ? (1.0 - opt_.light_ambient) * count / sum : 0.0;
}

double Scene::illumination(const Eigen::Vector3d &p, const Eigen::Vector3d &n) const {
  if (lamps_.empty())
    return 1.0;
  double e = 0.0;
  for (const Lamp &l : lamps_) {
    const Eigen::Vector3d d = l.position - p;
    const double r = d.norm();
    if (r < 1e-6)
      continue;
    const double cos_lamp = std::max(0.0, d.z() / r), cos_face = std::max(0.0, n.dot(d) / r);
    e += cos_lamp * cos_face / (r * r + 1.0); // a broad fitting, not a point: no hot spots under it
  }
  return opt_.light_ambient + lamp_gain_ * e;
}

void Scene::bake_lighting(Surface &s, const Eigen::Vector3d &normal) const {
  // Illumination varies over tens of centimetres: evaluate it every 0.1 m and interpolate.
  cv::Mat &tex = s.mips[0];
  const double cell = 0.1;
  const int gw = static_cast<int>(std::ceil(s.size_u / cell)) + 2,
            gh = static_cast<int>(std::ceil(s.size_v / cell)) + 2;
  cv::Mat grid(gh, gw, CV_32F);
  for (int j = 0; j < gh; ++j)
    for (int i = 0; i < gw; ++i)
      grid.at<float>(j, i) =
          static_cast<float>(illumination(surface_point_of(s, (i - 0.5) * cell, (j - 0.5) * cell), normal));
  cv::Mat light, f;
  cv::resize(
      grid, light,
      cv::Size(static_cast<int>(gw * cell / opt_.texture.texel_m), static_cast<int>(gh * cell / opt_.texture.texel_m)),
      0, 0, cv::INTER_LINEAR);
  const int off = static_cast<int>(0.5 * cell / opt_.texture.texel_m);
  tex.convertTo(f, CV_32F, kLitScale);
  f = f.mul(light(cv::Rect(off, off, tex.cols, tex.rows)));
  // Lamps on the ceiling are bright panels (they saturate when the camera looks up, and auto-exposure reacts).
  if (s.axis == 2 && normal.z() < 0)
    for (const Lamp &l : lamps_) {
      const double u = l.position(s.axis_u) - s.origin(s.axis_u), v = l.position(s.axis_v) - s.origin(s.axis_v);
      const auto px = [&](double m) { return static_cast<int>(std::lround(m / opt_.texture.texel_m)); };
      cv::rectangle(f, cv::Point(px(u - 0.3), px(v - 0.15)), cv::Point(px(u + 0.3), px(v + 0.15)), cv::Scalar(255),
                    cv::FILLED);
    }
  f.convertTo(tex, CV_8U);
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
  return surface_point_of(surfaces_.at(surface), u, v);
}

Eigen::Vector3d surface_point_of(const Surface &s, double u, double v) {
  Eigen::Vector3d p = s.origin;
  p(s.axis_u) += u;
  p(s.axis_v) += v;
  return p;
}

Eigen::Vector3d Scene::plant_marker(int surface, double u, double v, double radius_m) {
  Surface &s = surfaces_.at(surface);
  const int shift = 8; // sub-texel centre, so the marker sits exactly where asked
  const double x = u / opt_.texture.texel_m - 0.5, y = v / opt_.texture.texel_m - 0.5;
  const cv::Point c(static_cast<int>(std::lround(x * (1 << shift))), static_cast<int>(std::lround(y * (1 << shift))));
  const auto r = [&](double m) { return static_cast<int>(std::lround(m / opt_.texture.texel_m * (1 << shift))); };
  cv::circle(s.mips[0], c, r(2.0 * radius_m), cv::Scalar(255), cv::FILLED, cv::LINE_AA, shift);
  cv::circle(s.mips[0], c, r(radius_m), cv::Scalar(0), cv::FILLED, cv::LINE_AA, shift);
  build_mips(s);
  return surface_point(surface, u, v);
}

} // namespace ovton::sim
