#include "ov_sim/renderer.h"
#include "ov_sim/hash_noise.h"

#include "ov_core/types/errors.h"
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

namespace ovton::sim {

namespace {

/// log2 to ~0.01: exponent bits plus a quadratic on the mantissa. Mip selection needs no more.
inline float fast_log2(float x) {
  uint32_t i;
  std::memcpy(&i, &x, 4);
  const float e = static_cast<float>(static_cast<int>((i >> 23) & 255) - 128);
  i = (i & 0x007FFFFFu) | 0x3F800000u;
  float m;
  std::memcpy(&m, &i, 4);
  return e + ((-1.0f / 3.0f) * m + 2.0f) * m - 2.0f / 3.0f;
}

/// Mip levels per surface the ray caster looks at.
constexpr int kMaxLevels = 16;

/// 1 / 2^l, exact (powers of two): the mip scale without a division per pixel.
constexpr std::array<float, kMaxLevels> kInvPow2 = [] {
  std::array<float, kMaxLevels> a{};
  float v = 1.0f;
  for (float &x : a) {
    x = v;
    v *= 0.5f;
  }
  return a;
}();

struct Level {
  const uint8_t *data;
  int w, h;
  size_t step;
};

inline float bilinear(const Level &L, float x, float y) {
  x = std::clamp(x, 0.0f, static_cast<float>(L.w - 1));
  y = std::clamp(y, 0.0f, static_cast<float>(L.h - 1));
  const int x0 = std::min(static_cast<int>(x), L.w - 2), y0 = std::min(static_cast<int>(y), L.h - 2);
  const float fx = x - x0, fy = y - y0;
  const uint8_t *r0 = L.data + y0 * L.step + x0, *r1 = r0 + L.step;
  const float a = r0[0] + fx * (r0[1] - r0[0]);
  const float b = r1[0] + fx * (r1[1] - r1[0]);
  return a + fy * (b - a);
}

} // namespace

Renderer::Renderer(const ovton::core::CameraModel &cam, const Scene &scene, const RenderOptions &opt)
    : cam_(cam), scene_(scene), opt_(opt) {
  const int w = cam.width(), h = cam.height();
  rays_.resize(static_cast<size_t>(w) * h);
  row_yn_lo_.assign(h, std::numeric_limits<float>::infinity());
  row_yn_hi_.assign(h, -std::numeric_limits<float>::infinity());
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector2d xn = cam.undistort(Eigen::Vector2d(u, v));
      const Eigen::Vector3d r = Eigen::Vector3d(xn.x(), xn.y(), 1.0).normalized();
      // Angular size from the neighbouring pixel: distortion stretches pixels towards the border.
      const Eigen::Vector2d xn1 = cam.undistort(Eigen::Vector2d(u + 1, v));
      const double ang = std::acos(std::clamp(r.dot(Eigen::Vector3d(xn1.x(), xn1.y(), 1.0).normalized()), -1.0, 1.0));
      Ray &R = rays_[static_cast<size_t>(v) * w + u];
      R.x = static_cast<float>(r.x());
      R.y = static_cast<float>(r.y());
      R.z = static_cast<float>(r.z());
      R.xn = static_cast<float>(xn.x());
      R.yn = static_cast<float>(xn.y());
      R.log2_pix = static_cast<float>(std::log2(std::max(ang, 1e-9)));
      row_yn_lo_[v] = std::min(row_yn_lo_[v], R.yn);
      row_yn_hi_[v] = std::max(row_yn_hi_[v], R.yn);
    }
  }
}

void Renderer::render(const Eigen::Matrix3d &R_WC, const Eigen::Vector3d &p_WC, uint64_t noise_seed,
                      cv::Mat &out) const {
  out.create(cam_.height(), cam_.width(), CV_8U);
  render_rows(R_WC, p_WC, 0, cam_.height(), noise_seed, out);
}

void Renderer::render(const FramePose &pose, uint64_t noise_seed, cv::Mat &out) const {
  if (!pose.at_row) {
    render(pose.R_WC, pose.p_WC, noise_seed, out);
    return;
  }
  // One pose per row; the per-frame tables below are rebuilt per row (boxes and mip levels: cheap next to a row of
  // ray casts).
  out.create(cam_.height(), cam_.width(), CV_8U);
  Eigen::Matrix3d R_WC;
  Eigen::Vector3d p_WC;
  for (int v = 0; v < cam_.height(); ++v) {
    pose.at_row(static_cast<double>(v), R_WC, p_WC);
    render_rows(R_WC, p_WC, v, v + 1, noise_seed, out);
  }
}

void Renderer::accumulate(const FramePose &pose, float weight, cv::Mat &acc) const {
  if (acc.rows != cam_.height() || acc.cols != cam_.width() || acc.type() != CV_32F)
    throw ovton::core::UsageError("renderer: the accumulator must be a CV_32F image of the camera's size");
  const auto sink = [&acc, weight](int u, int v, float val) { acc.ptr<float>(v)[u] += weight * val; };
  if (!pose.at_row) {
    cast_rows(pose.R_WC, pose.p_WC, 0, cam_.height(), sink);
    return;
  }
  Eigen::Matrix3d R_WC;
  Eigen::Vector3d p_WC;
  for (int v = 0; v < cam_.height(); ++v) {
    pose.at_row(static_cast<double>(v), R_WC, p_WC);
    cast_rows(R_WC, p_WC, v, v + 1, sink);
  }
}

void Renderer::render_rows(const Eigen::Matrix3d &R_WC, const Eigen::Vector3d &p_WC, int v_begin, int v_end,
                           uint64_t noise_seed, cv::Mat &out) const {
  // (U1 + U2 - 65535) for U uniform on [0, 65535] has sigma 65536 / sqrt(6).
  const float noise_scale = static_cast<float>(opt_.noise_sigma * std::sqrt(6.0) / 65536.0);
  const int w = cam_.width();
  cast_rows(R_WC, p_WC, v_begin, v_end, [&](int u, int v, float val) {
    if (noise_scale > 0.0f) {
      // Sum of two uniforms (triangular, sigma as requested): cheap, deterministic per pixel and frame.
      const uint32_t hh = hash32(noise_key(noise_seed, static_cast<uint64_t>(v) * w + u));
      val += noise_scale * (static_cast<float>(hh & 0xFFFF) + static_cast<float>(hh >> 16) - 65535.0f);
    }
    out.ptr<uint8_t>(v)[u] = static_cast<uint8_t>(std::clamp(val + 0.5f, 0.0f, 255.0f));
  });
}

template <typename Sink>
void Renderer::cast_rows(const Eigen::Matrix3d &R_WC, const Eigen::Vector3d &p_WC, int v_begin, int v_end,
                         Sink &&sink) const {
  const int w = cam_.width();
  const auto &surfs = scene_.surfaces();
  const auto &boxes = scene_.boxes();
  const auto &room = scene_.room();

  // Per-frame tables: mip levels of every surface, and boxes with their image-plane bounds.
  std::vector<Level> levels(surfs.size() * kMaxLevels);
  std::vector<int> n_levels(surfs.size());
  for (size_t s = 0; s < surfs.size(); ++s) {
    n_levels[s] = std::min<int>(kMaxLevels, static_cast<int>(surfs[s].mips.size()));
    for (int l = 0; l < n_levels[s]; ++l) {
      const cv::Mat &m = surfs[s].mips[l];
      levels[s * kMaxLevels + l] = Level{m.data, m.cols, m.rows, m.step[0]};
    }
  }
  struct BoxCull {
    float lo[3], hi[3];
    float xmin, xmax, ymin, ymax; ///< normalised image-plane bounds; infinite when the box straddles z = 0
    int index;
  };
  std::vector<BoxCull> cull;
  const Eigen::Matrix3d R_CW = R_WC.transpose();
  for (size_t b = 0; b < boxes.size(); ++b) {
    BoxCull c;
    c.index = static_cast<int>(b);
    for (int a = 0; a < 3; ++a) {
      c.lo[a] = static_cast<float>(boxes[b].lo(a) - p_WC(a));
      c.hi[a] = static_cast<float>(boxes[b].hi(a) - p_WC(a));
    }
    int behind = 0, front = 0;
    double xmin = 1e30, xmax = -1e30, ymin = 1e30, ymax = -1e30;
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d corner((k & 1) ? boxes[b].hi.x() : boxes[b].lo.x(),
                                   (k & 2) ? boxes[b].hi.y() : boxes[b].lo.y(),
                                   (k & 4) ? boxes[b].hi.z() : boxes[b].lo.z());
      const Eigen::Vector3d pc = R_CW * (corner - p_WC);
      if (pc.z() <= 1e-3) {
        ++behind;
        continue;
      }
      ++front;
      xmin = std::min(xmin, pc.x() / pc.z());
      xmax = std::max(xmax, pc.x() / pc.z());
      ymin = std::min(ymin, pc.y() / pc.z());
      ymax = std::max(ymax, pc.y() / pc.z());
    }
    if (front == 0)
      continue; // entirely behind the camera
    if (behind > 0) {
      xmin = ymin = -1e30;
      xmax = ymax = 1e30;
    }
    c.xmin = static_cast<float>(xmin);
    c.xmax = static_cast<float>(xmax);
    c.ymin = static_cast<float>(ymin);
    c.ymax = static_cast<float>(ymax);
    cull.push_back(c);
  }

  const Eigen::Matrix3f R = R_WC.cast<float>();
  float rlo[3], rhi[3];
  for (int a = 0; a < 3; ++a) {
    rlo[a] = static_cast<float>(room.lo(a) - p_WC(a));
    rhi[a] = static_cast<float>(room.hi(a) - p_WC(a));
  }
  // Surface origins relative to the camera, so the hit point o + t d is just t d.
  std::vector<float> s_off(surfs.size() * 3);
  for (size_t s = 0; s < surfs.size(); ++s)
    for (int a = 0; a < 3; ++a)
      s_off[s * 3 + a] = static_cast<float>(surfs[s].origin(a) - p_WC(a));
  const float log2_texel = static_cast<float>(std::log2(scene_.texel_m()));
  const float inv_texel = static_cast<float>(1.0 / scene_.texel_m());
  const float lod_bias = static_cast<float>(opt_.lod_bias);
  const float inf = std::numeric_limits<float>::infinity();

  std::vector<BoxCull> row_cull;
  row_cull.reserve(cull.size());
  for (int v = v_begin; v < v_end; ++v) {
    // The boxes this row's rays can meet, in the same order: the per-pixel test below then skips the rest of the
    // scene without looking at it (the image is the same; most boxes cover a few rows).
    row_cull.clear();
    for (const BoxCull &c : cull)
      if (c.ymax >= row_yn_lo_[v] && c.ymin <= row_yn_hi_[v])
        row_cull.push_back(c);
    for (int u = 0; u < w; ++u) {
      const Ray &ray = rays_[static_cast<size_t>(v) * w + u];
      const float d[3] = {R(0, 0) * ray.x + R(0, 1) * ray.y + R(0, 2) * ray.z,
                          R(1, 0) * ray.x + R(1, 1) * ray.y + R(1, 2) * ray.z,
                          R(2, 0) * ray.x + R(2, 1) * ray.y + R(2, 2) * ray.z};
      const float inv[3] = {d[0] != 0.0f ? 1.0f / d[0] : inf, d[1] != 0.0f ? 1.0f / d[1] : inf,
                            d[2] != 0.0f ? 1.0f / d[2] : inf};
      // Room: leave through the nearest wall.
      float best = inf;
      int face = 0;
      for (int a = 0; a < 3; ++a) {
        const float t = (inv[a] > 0 ? rhi[a] : rlo[a]) * inv[a];
        if (t < best) {
          best = t;
          face = 2 * a + (inv[a] > 0 ? 1 : 0);
        }
      }
      // The slab test of Scene::intersect (the reference, in double), specialised for the hot loop: float, box
      // bounds pre-shifted to the camera centre, inverse directions from the ray table, screen-space culling.
      // tests/test_sim_render.cpp checks the rendered geometry against the camera model with planted markers.
      for (const BoxCull &c : row_cull) {
        if (ray.xn < c.xmin || ray.xn > c.xmax || ray.yn < c.ymin || ray.yn > c.ymax)
          continue;
        float tn = -inf, tf = inf;
        int an = 0;
        for (int a = 0; a < 3; ++a) {
          float t1 = c.lo[a] * inv[a], t2 = c.hi[a] * inv[a];
          if (t1 > t2)
            std::swap(t1, t2);
          if (t1 > tn) {
            tn = t1;
            an = a;
          }
          tf = std::min(tf, t2);
        }
        if (tn <= tf && tn > 0.0f && tn < best) {
          best = tn;
          face = Scene::face_index(c.index, an, d[an] < 0.0f);
        }
      }
      const Surface &S = surfs[face];
      const float su = best * d[S.axis_u] - s_off[face * 3 + S.axis_u];
      const float sv = best * d[S.axis_v] - s_off[face * 3 + S.axis_v];
      // Footprint of the pixel on the face, widened at grazing incidence (isotropic mip filter).
      const float cosi = std::max(std::fabs(d[S.axis]), 0.2f);
      float lod = fast_log2(best / cosi) + ray.log2_pix - log2_texel + lod_bias;
      const int nl = n_levels[face];
      lod = std::clamp(lod, 0.0f, static_cast<float>(nl - 1));
      const int l0 = std::min(static_cast<int>(lod), nl - 1), l1 = std::min(l0 + 1, nl - 1);
      const float fl = lod - l0;
      // Level l texel i is centred at level-0 coordinate 2^l i (cv::pyrDown keeps even samples).
      const float x0 = su * inv_texel - 0.5f, y0 = sv * inv_texel - 0.5f;
      const float sc0 = kInvPow2[l0], sc1 = kInvPow2[l1];
      float val = bilinear(levels[face * kMaxLevels + l0], x0 * sc0, y0 * sc0);
      if (fl > 0.0f)
        val += fl * (bilinear(levels[face * kMaxLevels + l1], x0 * sc1, y0 * sc1) - val);
      val *= S.shade;
      sink(u, v, val);
    }
  }
}

} // namespace ovton::sim
