#include "ov_sim/texture.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_codecs.h"
#include "ov_core/types/errors.h"
#include "ov_sim/hash_noise.h"
#include "ov_sim/random.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace ovton::sim {

const char *to_string(TextureStyle s) {
  return s == TextureStyle::Room ? "room" : "blotches";
}

TextureStyle parse_texture_style(const std::string &s) {
  if (s == "blotches")
    return TextureStyle::Blotches;
  if (s == "room")
    return TextureStyle::Room;
  throw ovton::core::UsageError("texture style must be blotches or room, not '" + s + "'");
}

/// Layers of randomly placed rectangles and discs, one layer per size octave, each added as a +/- offset so that
/// coarse structure survives under fine detail. After mip filtering, whatever the viewing distance, some octave is
/// near the pixel scale and gives KLT sharp corners with 15-95 grey-level contrast.
cv::Mat make_blotch_texture(int w, int h, const TextureOptions &opt, Rng &rng) {
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
      // Sign and size drawn in separate statements (the operands of * are unsequenced): sign first, gcc's order.
      const double sign = rng.uniform() < 0.5 ? -1.0 : 1.0;
      const short val = static_cast<short>(sign * amp * rng.uniform(0.6, 1.0));
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

namespace {

/// Paint albedo of a plain face, as a grey level: floors darker than walls, ceilings lightest.
double base_grey(FaceKind kind, Rng &rng) {
  switch (kind) {
  case FaceKind::Floor:
    return rng.uniform(70.0, 130.0);
  case FaceKind::Ceiling:
    return rng.uniform(170.0, 220.0);
  case FaceKind::Wall:
    return rng.uniform(120.0, 210.0);
  case FaceKind::Object:
    break;
  }
  return rng.uniform(60.0, 200.0);
}

/// Smooth random field of relative amplitude `amp` and feature size ~cell texels (bicubic upsampling of a coarse
/// random grid): stains, uneven paint, soft shading that real plain surfaces show.
void add_stains(cv::Mat &acc, double base, double amp, int cell, Rng &rng) {
  const int gw = acc.cols / cell + 3, gh = acc.rows / cell + 3;
  cv::Mat grid(gh, gw, CV_32F);
  for (int v = 0; v < gh; ++v)
    for (int u = 0; u < gw; ++u)
      grid.at<float>(v, u) = static_cast<float>(base * amp * rng.uniform(-1.0, 1.0));
  cv::Mat up;
  cv::resize(grid, up, cv::Size(gw * cell, gh * cell), 0, 0, cv::INTER_CUBIC);
  acc += up(cv::Rect(cell, cell, acc.cols, acc.rows));
}

/// Procedural print for posters and mats: the blotch texture at poster scale, on a light or dark ground.
cv::Mat poster_print(int w, int h, const TextureOptions &opt, Rng &rng) {
  TextureOptions po = opt;
  po.feature_min_m = 0.01;
  po.feature_max_m = std::max(0.02, 0.4 * std::min(w, h) * opt.texel_m);
  cv::Mat t = make_blotch_texture(w, h, po, rng);
  cv::Mat f;
  t.convertTo(f, CV_32F);
  return f;
}

/// A crop of a real frame scaled to w x h texels (its own blur and noise are part of what it brings).
cv::Mat poster_crop(int w, int h, const std::vector<cv::Mat> &crops, Rng &rng) {
  const cv::Mat &src = crops[rng.uniform_int(static_cast<int>(crops.size()))];
  const double aspect = static_cast<double>(w) / h;
  int cw = static_cast<int>(rng.uniform(0.25, 0.6) * src.cols);
  int ch = static_cast<int>(cw / aspect);
  if (ch > src.rows * 0.9) {
    ch = static_cast<int>(src.rows * 0.9);
    cw = static_cast<int>(ch * aspect);
  }
  cw = std::max(cw, 8);
  ch = std::max(ch, 8);
  const int x = rng.uniform_int(std::max(1, src.cols - cw)), y = rng.uniform_int(std::max(1, src.rows - ch));
  cv::Mat roi = src(cv::Rect(x, y, std::min(cw, src.cols - x), std::min(ch, src.rows - y))), f, out;
  roi.convertTo(f, CV_32F);
  cv::resize(f, out, cv::Size(w, h), 0, 0, cv::INTER_LINEAR);
  return out;
}

/// Pastes `patch` at (x, y) into acc, clipped to acc.
void paste(cv::Mat &acc, const cv::Mat &patch, int x, int y) {
  const cv::Rect dst = cv::Rect(x, y, patch.cols, patch.rows) & cv::Rect(0, 0, acc.cols, acc.rows);
  if (dst.empty())
    return;
  patch(cv::Rect(dst.x - x, dst.y - y, dst.width, dst.height)).copyTo(acc(dst));
}

/// Tape on the floor or a cable: a long dark strip with light square markers, like those on the EuRoC Vicon floor.
double draw_strip(cv::Mat &acc, double texel_m, Rng &rng) {
  const double len = rng.uniform(0.5, 2.5) / texel_m, wid = rng.uniform(0.03, 0.07) / texel_m;
  const double cx = rng.uniform(0.0, acc.cols), cy = rng.uniform(0.0, acc.rows), ang = rng.uniform(0.0, M_PI);
  const cv::RotatedRect r(cv::Point2f(static_cast<float>(cx), static_cast<float>(cy)),
                          cv::Size2f(static_cast<float>(len), static_cast<float>(wid)),
                          static_cast<float>(ang * 180.0 / M_PI));
  cv::Point2f c[4];
  r.points(c);
  std::vector<cv::Point> poly(c, c + 4);
  cv::fillConvexPoly(acc, poly, cv::Scalar(rng.uniform(15.0, 45.0)), cv::LINE_8);
  const double step = rng.uniform(0.06, 0.2) / texel_m, mark = 0.6 * wid;
  for (double s = -len / 2 + step / 2; s < len / 2; s += step) {
    const cv::Point2f m(static_cast<float>(cx + s * std::cos(ang)), static_cast<float>(cy + s * std::sin(ang)));
    const cv::RotatedRect sq(m, cv::Size2f(static_cast<float>(mark), static_cast<float>(mark)),
                             static_cast<float>(rng.uniform(0.0, 90.0)));
    sq.points(c);
    std::vector<cv::Point> q(c, c + 4);
    cv::fillConvexPoly(acc, q, cv::Scalar(rng.uniform(190.0, 240.0)), cv::LINE_8);
  }
  return len * wid;
}

/// A cluster of small objects (boxes, tools, papers): discs and rectangles of 2-12 cm, any grey.
double draw_clutter(cv::Mat &acc, double texel_m, Rng &rng) {
  const double size = rng.uniform(0.3, 1.0) / texel_m;
  const double cx = rng.uniform(0.0, acc.cols), cy = rng.uniform(0.0, acc.rows);
  const int n = 5 + rng.uniform_int(25);
  for (int i = 0; i < n; ++i) {
    const double x = cx + rng.uniform(-0.5, 0.5) * size, y = cy + rng.uniform(-0.5, 0.5) * size;
    const double s = rng.uniform(0.02, 0.12) / texel_m;
    const cv::Scalar g(rng.uniform() < 0.5 ? rng.uniform(10.0, 70.0) : rng.uniform(170.0, 250.0));
    if (rng.uniform() < 0.6)
      cv::rectangle(acc, cv::Point(static_cast<int>(x), static_cast<int>(y)),
                    cv::Point(static_cast<int>(x + s), static_cast<int>(y + s * rng.uniform(0.3, 1.5))), g, cv::FILLED);
    else
      cv::circle(acc, cv::Point(static_cast<int>(x), static_cast<int>(y)), std::max(1, static_cast<int>(s / 2)), g,
                 cv::FILLED);
  }
  return 0.3 * size * size; // the items cover about a third of the cluster's square
}

/// A poster, mat or print: a framed rectangle of rich texture.
double draw_poster(cv::Mat &acc, const TextureOptions &opt, Rng &rng) {
  const double wm = rng.uniform(0.25, 1.3), hm = wm * rng.uniform(0.6, 1.6);
  const int w = std::max(4, static_cast<int>(wm / opt.texel_m)), h = std::max(4, static_cast<int>(hm / opt.texel_m));
  const int x = static_cast<int>(rng.uniform(-0.2 * w, acc.cols - 0.8 * w));
  const int y = static_cast<int>(rng.uniform(-0.2 * h, acc.rows - 0.8 * h));
  cv::Mat p = (opt.crops && !opt.crops->empty()) ? poster_crop(w, h, *opt.crops, rng) : poster_print(w, h, opt, rng);
  const int frame = std::max(1, static_cast<int>(0.01 / opt.texel_m));
  cv::rectangle(p, cv::Rect(0, 0, w, h), cv::Scalar(rng.uniform(20.0, 60.0)), frame);
  paste(acc, p, x, y);
  return static_cast<double>(w) * h;
}

/// Straight seams and edges (panel joints, skirting boards, door frames) across a face.
void draw_seams(cv::Mat &acc, double base, double texel_m, Rng &rng) {
  const int n = rng.uniform_int(3);
  for (int i = 0; i < n; ++i) {
    const bool vertical = rng.uniform() < 0.5;
    const int thick = std::max(1, static_cast<int>(rng.uniform(0.005, 0.03) / texel_m));
    const cv::Scalar g(base * rng.uniform(0.6, 0.85));
    if (vertical) {
      const int x = rng.uniform_int(acc.cols);
      cv::line(acc, cv::Point(x, 0), cv::Point(x, acc.rows - 1), g, thick);
    } else {
      const int y = rng.uniform_int(acc.rows);
      cv::line(acc, cv::Point(0, y), cv::Point(acc.cols - 1, y), g, thick);
    }
  }
}

} // namespace

cv::Mat make_room_texture(int w, int h, FaceKind kind, const TextureOptions &opt, Rng &rng) {
  if (!(opt.density >= 0.0 && opt.density <= 1.0))
    throw ovton::core::UsageError("texture density must lie in [0, 1]");
  const double base = base_grey(kind, rng);
  cv::Mat acc(h, w, CV_32F, cv::Scalar(base));
  // Stains at ~0.6 m, fading at room scale; then the grain of paint or fabric at texel scale.
  add_stains(acc, base, opt.stain, std::max(2, static_cast<int>(0.6 / opt.texel_m)), rng);
  draw_seams(acc, base, opt.texel_m, rng);
  // Textured patches until the requested share of the face is covered (overlaps make the share approximate).
  const double target = opt.density * static_cast<double>(w) * h;
  double covered = 0.0;
  for (int guard = 0; covered < target && guard < 10000; ++guard) {
    const double pick = rng.uniform();
    if (kind == FaceKind::Floor ? pick < 0.3 : pick < 0.15)
      covered += draw_strip(acc, opt.texel_m, rng);
    else if (pick < 0.45)
      covered += draw_clutter(acc, opt.texel_m, rng);
    else
      covered += draw_poster(acc, opt, rng);
  }
  if (opt.grain > 0.0) {
    // Grain in two scales, per-texel draws from a hash keyed by the face's stream: the weave of fabric or carpet
    // at ~2 cm (it survives mip filtering at a few metres, so plain surfaces still carry weak, trackable texture)
    // and paint speckle at texel scale.
    const uint64_t seed = rng.engine()();
    const int cell = std::max(1, static_cast<int>(std::lround(0.02 / opt.texel_m)));
    const int gw = w / cell + 2, gh = h / cell + 2;
    cv::Mat coarse(gh, gw, CV_32F), up;
    for (int v = 0; v < gh; ++v)
      for (int u = 0; u < gw; ++u)
        coarse.at<float>(v, u) = approx_normal(noise_key(seed, static_cast<uint64_t>(v) * gw + u));
    cv::resize(coarse, up, cv::Size(gw * cell, gh * cell), 0, 0, cv::INTER_CUBIC);
    const float g = static_cast<float>(opt.grain), gc = static_cast<float>(opt.grain * opt.weave);
    const uint64_t fine_seed = noise_key(seed, 0xF17E);
    for (int v = 0; v < h; ++v) {
      float *row = acc.ptr<float>(v);
      const float *c = up.ptr<float>(v);
      for (int u = 0; u < w; ++u)
        row[u] += gc * c[u] + g * approx_normal(noise_key(fine_seed, static_cast<uint64_t>(v) * w + u));
    }
  }
  cv::Mat tex;
  acc.convertTo(tex, CV_8U); // rounds and saturates
  return tex;
}

std::vector<cv::Mat> load_texture_crops(const std::string &euroc_dir, int count) {
  ovton::core::LoadOptions lo;
  const ovton::core::Dataset d = ovton::core::load_dataset(euroc_dir, lo);
  std::vector<cv::Mat> out;
  const size_t n = d.images.size();
  if (n == 0 || d.images.front().features)
    throw ovton::core::DataError(euroc_dir, "no cam0 images to take texture crops from");
  const size_t take = std::min<size_t>(n, static_cast<size_t>(std::max(1, count)));
  for (size_t i = 0; i < take; ++i) {
    const std::string &file = d.images[i * n / take].path;
    cv::Mat img = ovton::core::read_gray_image(file);
    if (img.empty())
      throw ovton::core::DataError(file, "cannot read image");
    out.push_back(img);
  }
  return out;
}

} // namespace ovton::sim
