#pragma once
// Textured box world for rendering and feature simulation: a room (interior faces) plus boxes standing on
// its floor. Every face is a Surface carrying its own procedural texture with a mip pyramid.
#include "ov_sim/texture.h"
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

namespace ovton::sim {

struct SceneOptions {
  double margin_xy_m = 2.0;    ///< room walls this far beyond the path's bounding box
  double margin_below_m = 1.0; ///< floor below the lowest path point
  double margin_above_m = 1.5; ///< ceiling above the highest path point
  double min_size_xy_m = 6.0;  ///< room never smaller than this (builtin: 6 x 6 x 3)
  double min_height_m = 3.0;
  int num_boxes = 10;           ///< objects for parallax (fewer if they do not fit beside the path)
  double box_clearance_m = 0.8; ///< minimum distance between any box and the path
  /// Blotches: the clean texture, evenly lit. Room: plain surfaces with textured patches (texture.h), lit by ceiling
  /// lamps (brightness baked into the textures: a diffuse scene looks the same from every side).
  TextureOptions texture;
  double light_ambient = 0.5; ///< Room: share of the mean illumination that is ambient (reaches every face)
  uint64_t seed = 0;
};

/// A ceiling lamp (Room style): a downward Lambertian emitter.
struct Lamp {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

/// An axis-aligned face: points origin + u * e_u + v * e_v, (u, v) in [0, size_u] x [0, size_v].
struct Surface {
  int axis = 0;               ///< normal axis (0 x, 1 y, 2 z)
  int axis_u = 1, axis_v = 2; ///< in-plane axes: (axis+1)%3, (axis+2)%3
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double size_u = 0.0, size_v = 0.0;
  float shade = 1.0f;        ///< per-face brightness, so faces meeting at an edge differ
  std::vector<cv::Mat> mips; ///< CV_8U; level 0 texel = texel_m; level l from cv::pyrDown
};

/// The world point at (u, v) of a face.
Eigen::Vector3d surface_point_of(const Surface &s, double u, double v);

struct AlignedBox {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
};

struct RayHit {
  double t = 0.0;   ///< distance along the (unit) ray
  int surface = -1; ///< index into Scene::surfaces()
  double u = 0.0, v = 0.0;
};

class Scene {
public:
  /// Room sized to enclose `path` (world positions) with margins, boxes placed away from the path.
  static Scene around_path(const std::vector<Eigen::Vector3d> &path, const SceneOptions &opt);
  Scene(const AlignedBox &room, const std::vector<AlignedBox> &boxes, const SceneOptions &opt);

  const AlignedBox &room() const { return room_; }
  const std::vector<AlignedBox> &boxes() const { return boxes_; }
  const std::vector<Surface> &surfaces() const { return surfaces_; }
  double texel_m() const { return opt_.texture.texel_m; }
  const SceneOptions &options() const { return opt_; }
  const std::vector<Lamp> &lamps() const { return lamps_; }

  /// Illumination of a point on a face with unit normal n (facing the viewer), relative to the room's mean
  /// (Room style; 1 everywhere for Blotches).
  double illumination(const Eigen::Vector3d &p, const Eigen::Vector3d &n) const;

  /// Surface index of face (2 * axis + (positive side ? 1 : 0)) of the room (box = -1) or of box `box`.
  static int face_index(int box, int axis, bool positive) { return 6 * (box + 1) + 2 * axis + (positive ? 1 : 0); }

  /// First surface hit by the ray o + t d (d unit, o inside the room). Returns false only if o is outside.
  bool raycast(const Eigen::Vector3d &o, const Eigen::Vector3d &d, RayHit &hit) const;
  Eigen::Vector3d surface_point(int surface, double u, double v) const;

  /// Paints a black disc of `radius_m` with a white ring out to 2 radius at (u, v) of a surface, for
  /// geometry tests; returns its centre in the world frame.
  Eigen::Vector3d plant_marker(int surface, double u, double v, double radius_m);

private:
  void add_face(const AlignedBox &b, int axis, bool positive, uint64_t seed);
  FaceKind face_kind(const AlignedBox &b, int axis, bool positive) const;
  void place_lamps();
  void bake_lighting(Surface &s, const Eigen::Vector3d &normal) const;
  static void build_mips(Surface &s);
  AlignedBox room_;
  std::vector<Lamp> lamps_;
  double lamp_gain_ = 0.0; ///< scales the lamps' sum so that the room's mean illumination is 1
  std::vector<AlignedBox> boxes_;
  std::vector<Surface> surfaces_;
  SceneOptions opt_;
};

} // namespace ovton::sim
