#pragma once
// Procedural surface textures (8-bit albedo maps, one texel = SceneOptions::texel_m).
//  - Blotches (`--realism clean`): every face covered wall to wall in random rectangles and discs at all scales.
//    Easy to track, unlike any real room: only 22 % of a rendered frame is plain, against 51 % of a real EuRoC one.
//  - Room (`--realism euroc`): what a real room looks like to a camera: large plain surfaces (uniform paint with a
//    faint grain and soft stains), and in places textured objects: posters and mats, tape strips with markers,
//    clusters of small clutter, seams. `density` is the share of a face covered by textured patches.
#include <Eigen/Core>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace ovton::sim {

class Rng;

enum class TextureStyle { Blotches, Room };
const char *to_string(TextureStyle s);
TextureStyle parse_texture_style(const std::string &s); ///< "blotches" | "room"; UsageError otherwise

/// What kind of face a texture covers: rooms have darker floors, light ceilings, objects with print on them.
enum class FaceKind { Floor, Ceiling, Wall, Object };

struct TextureOptions {
  TextureStyle style = TextureStyle::Blotches;
  double texel_m = 0.005;       ///< finest texture detail; EuRoC cam0 at 1 m sees 2.2 mm per pixel
  double feature_min_m = 0.015; ///< Blotches: smallest painted rectangle; largest is feature_max_m
  double feature_max_m = 0.6;
  double density = 0.3; ///< Room: share of each room face covered by textured patches [0, 1]
  double grain = 2.0;   ///< Room: grey-level sigma of the paint/fabric grain of plain surfaces, per texel
  double weave = 1.5;   ///< Room: the ~2 cm weave's sigma relative to `grain`
  double stain = 0.04;  ///< Room: relative amplitude of soft large-scale variation of plain surfaces
  /// Room: when set, posters are crops of these 8-bit grey images (e.g. real EuRoC frames) instead of procedural
  /// print. Shared, read-only.
  std::shared_ptr<const std::vector<cv::Mat>> crops;
};

/// Multi-octave blotches (the clean preset's texture), w x h texels. Draws from `rng` in a fixed order: the clean
/// renderings are byte-for-byte those of earlier versions.
cv::Mat make_blotch_texture(int w, int h, const TextureOptions &opt, Rng &rng);

/// A plain surface with textured patches, w x h texels.
cv::Mat make_room_texture(int w, int h, FaceKind kind, const TextureOptions &opt, Rng &rng);

/// Up to `count` frames of an EuRoC folder's cam0, evenly spaced, as 8-bit grey (for TextureOptions::crops).
/// Throws DataError when the folder cannot be read or holds no images.
std::vector<cv::Mat> load_texture_crops(const std::string &euroc_dir, int count = 24);

} // namespace ovton::sim
