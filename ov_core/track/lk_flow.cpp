#include "ov_core/track/lk_flow.h"
#include "ov_core/types/errors.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#ifdef __AVX2__
#include <immintrin.h>
#endif

namespace ovton::core {
namespace {

// Eight floats: GCC/clang vector extensions, compiled to one AVX register where the build has AVX2 (OVTON_AVX2) and to
// two SSE registers otherwise. This file is built with FP contraction on (CMakeLists.txt), so a*b + c is one FMA.
typedef float v8f __attribute__((vector_size(32)));
typedef unsigned char v8u __attribute__((vector_size(8)));

inline v8f load8(const float *p) {
  v8f v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void store8(float *p, v8f v) {
  std::memcpy(p, &v, sizeof v);
}
inline v8f splat(float x) {
  return v8f{x, x, x, x, x, x, x, x};
}
inline float hsum(v8f v) {
  return ((v[0] + v[1]) + (v[2] + v[3])) + ((v[4] + v[5]) + (v[6] + v[7]));
}

/// Eight grey values as floats. (GCC turns __builtin_convertvector of bytes into eight scalar conversions.)
inline v8f bytes_to_floats(const unsigned char *p) {
#ifdef __AVX2__
  v8f v;
  const __m256 f = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i *>(p))));
  std::memcpy(&v, &f, sizeof v);
  return v;
#else
  v8u u;
  std::memcpy(&u, p, sizeof u);
  return __builtin_convertvector(u, v8f);
#endif
}

/// Bilinear interpolation of 8 consecutive pixels starting at p (weights of the pixel, its right, lower and
/// lower-right neighbours).
inline v8f bilinear(const float *p, int stride, v8f w00, v8f w01, v8f w10, v8f w11) {
  return w00 * load8(p) + w01 * load8(p + 1) + w10 * load8(p + stride) + w11 * load8(p + stride + 1);
}

// OpenCV's scale of the gradient sums (its A and b are in units of 2^-20 of raw Scharr values times grey levels x 32):
// kept so that min_eig means what OpenCV's minEigThreshold means.
constexpr float kFltScale = 1.f / (1 << 20);

struct Weights {
  v8f w00, w01, w10, w11;
  explicit Weights(float a, float b)
      : w00(splat((1.f - a) * (1.f - b))), w01(splat(a * (1.f - b))), w10(splat((1.f - a) * b)), w11(splat(a * b)) {}
};

/// Scharr derivatives (OpenCV's calcSharrDeriv: [3 10 3] smoothing across, central difference along) of the 8
/// pixels starting at row pointer r1 (r0, r2: the rows above and below, same column).
inline void scharr8(const float *r0, const float *r1, const float *r2, v8f &dx, v8f &dy) {
  const v8f three = splat(3.f), ten = splat(10.f);
  const v8f smooth_l = three * (load8(r0 - 1) + load8(r2 - 1)) + ten * load8(r1 - 1);
  const v8f smooth_r = three * (load8(r0 + 1) + load8(r2 + 1)) + ten * load8(r1 + 1);
  dx = smooth_r - smooth_l;
  dy = three * ((load8(r2 - 1) - load8(r0 - 1)) + (load8(r2 + 1) - load8(r0 + 1))) + ten * (load8(r2) - load8(r0));
}

/// The window of one point at one level of the first image: grey values and derivatives, `nv` vectors per row with
/// the lanes beyond the window zero; and the scratch grid of derivatives at whole pixels they are interpolated from.
struct Patch {
  int win = 0, nv = 0;
  int ng = 0, gw = 0; ///< grid: vectors per row (the window and one column more), floats per row
  v8f last_mask{};    ///< 1 in the lanes of a row's last vector that lie in the window, 0 beyond
  std::vector<float> g, gx, gy, grid_x, grid_y;
  void resize(int w) {
    win = w;
    nv = (w + 7) / 8;
    for (int l = 0; l < 8; ++l)
      last_mask[l] = (nv - 1) * 8 + l < win ? 1.f : 0.f;
    ng = (w + 1 + 7) / 8;
    gw = ng * 8 + 8;
    const size_t n = static_cast<size_t>(win) * static_cast<size_t>(nv) * 8;
    g.resize(n);
    gx.resize(n);
    gy.resize(n);
    // Lanes past the grid's last vector are read (as the right neighbour of masked lanes) but never written: zero.
    grid_x.assign(static_cast<size_t>(win + 1) * static_cast<size_t>(gw), 0.f);
    grid_y.assign(grid_x.size(), 0.f);
  }

  /// The derivatives at whole pixels (ix .. ix + 8 ng - 1, iy .. iy + win) of level I, 0 outside the level as
  /// OpenCV's border. Computed here from the grey values rather than kept as planes for the whole pyramid: the
  /// windows cover a fraction of the image, and two more planes of floats per image cost more memory traffic than
  /// these few hundred vectors (measured, docs/benchmarks.md).
  void derivative_grid(const LkPyramid::Level &I, int ix, int iy) {
    for (int r = 0; r <= win; ++r) {
      const int y = iy + r;
      float *ox = &grid_x[static_cast<size_t>(r) * static_cast<size_t>(gw)];
      float *oy = &grid_y[static_cast<size_t>(r) * static_cast<size_t>(gw)];
      if (y < 0 || y >= I.rows) {
        std::fill(ox, ox + 8 * ng, 0.f);
        std::fill(oy, oy + 8 * ng, 0.f);
        continue;
      }
      const float *r0 = I.at(ix, y - 1), *r1 = I.at(ix, y), *r2 = I.at(ix, y + 1);
      for (int k = 0; k < ng; ++k) {
        v8f dx, dy;
        scharr8(r0 + 8 * k, r1 + 8 * k, r2 + 8 * k, dx, dy);
        const int x0 = ix + 8 * k;
        if (x0 < 0 || x0 + 8 > I.cols) {
          v8f inside;
          for (int l = 0; l < 8; ++l)
            inside[l] = x0 + l >= 0 && x0 + l < I.cols ? 1.f : 0.f;
          dx *= inside;
          dy *= inside;
        }
        store8(ox + 8 * k, dx);
        store8(oy + 8 * k, dy);
      }
    }
  }
};

/// The gradient matrix of a window (OpenCV's A, in its units).
struct Gradient {
  float A11 = 0, A12 = 0, A22 = 0;
};

/// Fills `patch` with the first image's window whose top-left corner is at (x, y) of level I (sub-pixel) and returns
/// its gradient matrix.
Gradient extract_window(const LkPyramid::Level &I, float x, float y, Patch &patch) {
  const int ix = static_cast<int>(std::floor(x)), iy = static_cast<int>(std::floor(y));
  const Weights w(x - static_cast<float>(ix), y - static_cast<float>(iy));
  patch.derivative_grid(I, ix, iy);
  const int nv = patch.nv;
  v8f a11 = splat(0.f), a12 = splat(0.f), a22 = splat(0.f);
  for (int r = 0; r < patch.win; ++r) {
    const float *src = I.at(ix, iy + r);
    const float *sx = &patch.grid_x[static_cast<size_t>(r) * static_cast<size_t>(patch.gw)];
    const float *sy = &patch.grid_y[static_cast<size_t>(r) * static_cast<size_t>(patch.gw)];
    const size_t row = static_cast<size_t>(r) * static_cast<size_t>(nv) * 8;
    for (int k = 0; k < nv; ++k) {
      v8f g = bilinear(src + 8 * k, I.stride, w.w00, w.w01, w.w10, w.w11);
      v8f gx = bilinear(sx + 8 * k, patch.gw, w.w00, w.w01, w.w10, w.w11);
      v8f gy = bilinear(sy + 8 * k, patch.gw, w.w00, w.w01, w.w10, w.w11);
      if (k == nv - 1) {
        g *= patch.last_mask;
        gx *= patch.last_mask;
        gy *= patch.last_mask;
      }
      store8(&patch.g[row + 8 * k], g);
      store8(&patch.gx[row + 8 * k], gx);
      store8(&patch.gy[row + 8 * k], gy);
      a11 += gx * gx;
      a12 += gx * gy;
      a22 += gy * gy;
    }
  }
  return {hsum(a11) * kFltScale, hsum(a12) * kFltScale, hsum(a22) * kFltScale};
}

bool outside(int ix, int iy, int win, const LkPyramid::Level &l) {
  return ix < -win || ix >= l.cols || iy < -win || iy >= l.rows;
}

/// Gauss-Newton on level J from the window's top-left corner `nxt`, with the window in `patch`, its gradient matrix
/// `A` and D = 1 / det A; `next_pt` follows every step (the window's centre, `half` from its corner). False when the
/// window leaves the level.
bool gauss_newton(const LkPyramid::Level &J, const Patch &patch, const Gradient &A, float D, cv::Point2f nxt,
                  float half, int max_iter, double eps2, cv::Point2f &next_pt) {
  const int nv = patch.nv;
  cv::Point2f prev_delta;
  for (int j = 0; j < max_iter; ++j) {
    const int jx = static_cast<int>(std::floor(nxt.x)), jy = static_cast<int>(std::floor(nxt.y));
    if (outside(jx, jy, patch.win, J))
      return false;
    const Weights w(nxt.x - static_cast<float>(jx), nxt.y - static_cast<float>(jy));
    v8f b1v = splat(0.f), b2v = splat(0.f);
    for (int r = 0; r < patch.win; ++r) {
      const float *src = J.at(jx, jy + r);
      const size_t row = static_cast<size_t>(r) * static_cast<size_t>(nv) * 8;
      for (int k = 0; k < nv; ++k) {
        const v8f diff = bilinear(src + 8 * k, J.stride, w.w00, w.w01, w.w10, w.w11) - load8(&patch.g[row + 8 * k]);
        b1v += diff * load8(&patch.gx[row + 8 * k]);
        b2v += diff * load8(&patch.gy[row + 8 * k]);
      }
    }
    const float b1 = hsum(b1v) * (32.f * kFltScale), b2 = hsum(b2v) * (32.f * kFltScale);
    const cv::Point2f delta((A.A12 * b2 - A.A22 * b1) * D, (A.A12 * b1 - A.A11 * b2) * D);
    nxt += delta;
    next_pt = nxt + cv::Point2f(half, half);
    if (delta.ddot(delta) <= eps2)
      break;
    if (j > 0 && std::abs(delta.x + prev_delta.x) < 0.01f && std::abs(delta.y + prev_delta.y) < 0.01f) {
      // Oscillating between two points: take the middle.
      next_pt -= delta * 0.5f;
      break;
    }
    prev_delta = delta;
  }
  return true;
}

void track_point(const LkPyramid &prev, const LkPyramid &next, const cv::Point2f &pt, cv::Point2f &next_pt,
                 unsigned char &status, const LkParams &p, int max_level, int max_iter, double eps2, Patch &patch) {
  const int win = p.win;
  const float half = (win - 1) * 0.5f;
  for (int level = max_level; level >= 0; --level) {
    const LkPyramid::Level &I = prev.level(level);
    const float scale = static_cast<float>(1. / (1 << level));
    const cv::Point2f prev_pt = pt * scale - cv::Point2f(half, half);
    const cv::Point2f nxt = level == max_level ? (p.use_initial ? next_pt * scale : pt * scale) : next_pt * 2.f;
    next_pt = nxt;
    // A point is lost only at the finest level; at a coarser one it goes on from where it is.
    bool found = false;
    if (!outside(static_cast<int>(std::floor(prev_pt.x)), static_cast<int>(std::floor(prev_pt.y)), win, I)) {
      const Gradient A = extract_window(I, prev_pt.x, prev_pt.y, patch);
      const float det = A.A11 * A.A22 - A.A12 * A.A12;
      const float min_eig = (A.A22 + A.A11 - std::sqrt((A.A11 - A.A22) * (A.A11 - A.A22) + 4.f * A.A12 * A.A12)) /
                            static_cast<float>(2 * win * win);
      found = min_eig >= p.min_eig && det >= FLT_EPSILON &&
              gauss_newton(next.level(level), patch, A, 1.f / det, nxt - cv::Point2f(half, half), half, max_iter, eps2,
                           next_pt);
    }
    if (!found && level == 0)
      status = 0;
  }
}

} // namespace

void LkPyramid::build(const std::vector<cv::Mat> &levels, int win) {
  win_ = win;
  levels_.resize(levels.size());
  for (size_t li = 0; li < levels.size(); ++li) {
    const cv::Mat &src = levels[li];
    if (src.type() != CV_8UC1)
      throw UsageError("LkPyramid: expected 8-bit single-channel pyramid levels (built without derivatives)");
    cv::Size whole;
    cv::Point ofs;
    src.locateROI(whole, ofs);
    if (ofs.x < win || ofs.y < win || ofs.x + src.cols + win > whole.width || ofs.y + src.rows + win > whole.height)
      throw UsageError("LkPyramid: a pyramid level is not padded by the window (cv::buildOpticalFlowPyramid)");
    Level &L = levels_[li];
    // Left and top: the window may start `win` before the image, and its derivatives read one pixel more. Right: a
    // window starting on the last column reads whole vectors (up to 7 lanes more than the window) and one column more
    // for the interpolation. Bottom: one row for the interpolation and one for the derivatives.
    const int left = win + 1, right = win + 16, top = win + 1, bottom = win + 2;
    const int stride = (src.cols + left + right + 7) / 8 * 8;
    if (L.cols != src.cols || L.rows != src.rows || L.stride != stride || L.img.empty()) {
      // A new layout: zeros everywhere. What lies beyond the padded image is never written again (it is read only
      // into lanes and derivatives that are masked), so the next images of the same size overwrite the rest.
      L.cols = src.cols;
      L.rows = src.rows;
      L.stride = stride;
      L.origin = top * L.stride + left;
      const size_t size = static_cast<size_t>(L.rows + top + bottom) * static_cast<size_t>(L.stride);
      L.img.assign(size, 0.f);
    }
    // Grey values over the padded level (the pyramid's own reflected border).
    const ptrdiff_t step = static_cast<ptrdiff_t>(src.step[0]);
    const int padded = L.cols + 2 * win;
    for (int y = -win; y < L.rows + win; ++y) {
      const unsigned char *s = src.data + y * step - win;
      float *d = L.at(-win, y);
      int x = 0;
      for (; x + 8 <= padded; x += 8)
        store8(d + x, bytes_to_floats(s + x));
      for (; x < padded; ++x)
        d[x] = s[x];
    }
  }
}

void lk_flow(const LkPyramid &prev, const LkPyramid &next, const std::vector<cv::Point2f> &pts,
             std::vector<cv::Point2f> &next_pts, std::vector<unsigned char> &status, const LkParams &p) {
  const size_t n = pts.size();
  if (p.use_initial && next_pts.size() != n)
    throw UsageError("lk_flow: use_initial needs one starting point per point");
  next_pts.resize(n);
  status.assign(n, 1);
  if (n == 0)
    return;
  if (prev.empty() || next.empty() || p.win < 3)
    throw UsageError("lk_flow: empty pyramid or window below 3 px");
  if (p.win > prev.window() || p.win > next.window())
    throw UsageError("lk_flow: window larger than the one the pyramids were built for");
  const int max_level = std::min(std::max(p.max_level, 0), std::min(prev.num_levels(), next.num_levels()) - 1);
  for (int l = 0; l <= max_level; ++l)
    if (prev.level(l).cols != next.level(l).cols || prev.level(l).rows != next.level(l).rows)
      throw UsageError("lk_flow: the two pyramids differ in size");
  const int max_iter = std::min(std::max(p.max_iter, 0), 100);
  const double eps = std::min(std::max(p.eps, 0.), 10.);
  cv::parallel_for_(cv::Range(0, static_cast<int>(n)), [&](const cv::Range &r) {
    Patch patch;
    patch.resize(p.win);
    for (int i = r.start; i < r.end; ++i)
      track_point(prev, next, pts[static_cast<size_t>(i)], next_pts[static_cast<size_t>(i)],
                  status[static_cast<size_t>(i)], p, max_level, max_iter, eps * eps, patch);
  });
}

} // namespace ovton::core
