#include "ov_eval/plot.h"
#include "ov_core/io/image_codecs.h"
#include "ov_core/types/errors.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <utility>

namespace ovton::eval {
namespace {

const cv::Scalar kWhite(255, 255, 255), kInk(30, 30, 30), kGrid(228, 228, 228), kBorder(150, 150, 150);
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kTickScale = 0.45, kLabelScale = 0.55, kTitleScale = 0.7;
constexpr int kShift = 4; // sub-pixel bits for OpenCV drawing, so anti-aliased lines sit where the mapping says
constexpr double kOne = 1 << kShift;

cv::Point fixed(double x, double y) {
  return {int(std::lround(x * kOne)), int(std::lround(y * kOne))};
}
bool finite(double x, double y) {
  return std::isfinite(x) && std::isfinite(y);
}

int ticks_for(int px, int px_per_tick) {
  return std::max(2, px / px_per_tick);
}

/// Labels share one format per axis, with just enough digits to tell neighbouring ticks apart.
std::vector<std::string> tick_labels(const std::vector<double> &ticks) {
  std::vector<std::string> out;
  if (ticks.empty())
    return out;
  const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : std::max(std::abs(ticks[0]), 1.0);
  double max_abs = 0;
  for (double t : ticks)
    max_abs = std::max(max_abs, std::abs(t));
  const int decimals = std::max(0, int(-std::floor(std::log10(step) + 1e-9)));
  const bool general = decimals > 5 || max_abs >= 1e12; // fixed point keeps seconds-since-epoch stamps readable
  const int digits = max_abs > 0 ? int(std::floor(std::log10(max_abs)) - std::floor(std::log10(step))) + 1 : 1;
  char buf[64];
  for (double t : ticks) {
    if (general)
      std::snprintf(buf, sizeof(buf), "%.*g", std::clamp(digits, 1, 15), t);
    else
      std::snprintf(buf, sizeof(buf), "%.*f", decimals, t);
    out.emplace_back(buf);
  }
  return out;
}

cv::Size text_size(const std::string &s, double scale) {
  int base = 0;
  cv::Size sz = cv::getTextSize(s, kFont, scale, 1, &base);
  return {sz.width, sz.height + base};
}

void text(cv::Mat &img, const std::string &s, cv::Point at, double scale) {
  cv::putText(img, s, at, kFont, scale, kInk, 1, cv::LINE_AA);
}

/// Liang-Barsky clip of a segment to the rectangle [x0, x1] x [y0, y1]; false when nothing is left. Needed because
/// OpenCV takes int coordinates, and a far-off data point would overflow them before OpenCV could clip.
bool clip(double &ax, double &ay, double &bx, double &by, double x0, double y0, double x1, double y1) {
  double t0 = 0, t1 = 1;
  const double dx = bx - ax, dy = by - ay;
  const double p[4] = {-dx, dx, -dy, dy}, q[4] = {ax - x0, x1 - ax, ay - y0, y1 - ay};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) {
      if (q[i] < 0)
        return false;
      continue;
    }
    const double r = q[i] / p[i];
    if (p[i] < 0)
      t0 = std::max(t0, r);
    else
      t1 = std::min(t1, r);
    if (t0 > t1)
      return false;
  }
  const double sx = ax, sy = ay;
  ax = sx + t0 * dx, ay = sy + t0 * dy, bx = sx + t1 * dx, by = sy + t1 * dy;
  return true;
}

/// Draws a segment (in the coordinates of `roi`), solid or dashed, clipped to a slightly enlarged roi.
void segment(cv::Mat &roi, double ax, double ay, double bx, double by, const cv::Scalar &c, int thick, bool dashed) {
  const double m = 4.0 + thick;
  if (!clip(ax, ay, bx, by, -m, -m, roi.cols + m, roi.rows + m))
    return;
  if (!dashed) {
    cv::line(roi, fixed(ax, ay), fixed(bx, by), c, thick, cv::LINE_AA, kShift);
    return;
  }
  const double len = std::hypot(bx - ax, by - ay), dash = 9, gap = 5;
  for (double s = 0; s < len; s += dash + gap) {
    const double e = std::min(len, s + dash);
    cv::line(roi, fixed(ax + (bx - ax) * s / len, ay + (by - ay) * s / len),
             fixed(ax + (bx - ax) * e / len, ay + (by - ay) * e / len), c, thick, cv::LINE_AA, kShift);
  }
}

int thickness(double width) {
  return std::max(1, int(std::lround(width)));
}

void check_range(const std::optional<AxisRange> &r, const char *axis) {
  if (r && !(std::isfinite(r->lo) && std::isfinite(r->hi) && r->lo < r->hi))
    throw ovton::core::UsageError(std::string("plot: the fixed ") + axis + " range must be finite with lo < hi");
}

} // namespace

std::vector<double> nice_ticks(double lo, double hi, int max_ticks) {
  if (!(std::isfinite(lo) && std::isfinite(hi) && lo < hi) || max_ticks < 2)
    throw ovton::core::UsageError("nice_ticks: need finite lo < hi and max_ticks >= 2");
  // The smallest nice step that leaves at most max_ticks ticks, preferring at least two; steps from a decade below
  // span / (max_ticks - 1) up, since a span whose ends sit on multiples fits one more tick than the rough count says.
  const double mag = std::pow(10.0, std::floor(std::log10((hi - lo) / (max_ticks - 1))));
  std::vector<double> ticks, fallback;
  for (double m : {0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0}) {
    const double step = m * mag;
    const double k0 = std::ceil(lo / step - 1e-9), k1 = std::floor(hi / step + 1e-9), n = k1 - k0 + 1;
    if (n > max_ticks || n < 1)
      continue;
    for (double k = k0; k <= k1; ++k)
      ticks.push_back(k * step + 0.0); // + 0.0 turns -0 into 0, so no "-0.0" label
    if (n >= 2)
      return ticks;
    if (fallback.empty())
      fallback.swap(ticks);
    ticks.clear();
  }
  return fallback;
}

cv::Scalar palette_color(size_t i) {
  static const cv::Scalar kPalette[8] = {{180, 119, 31},  {14, 127, 255}, {44, 160, 44},   {40, 39, 214},
                                         {189, 103, 148}, {75, 86, 140},  {194, 119, 227}, {207, 190, 23}};
  return kPalette[i % 8];
}

Plot::Plot(PlotOptions options) : options_(std::move(options)) {
  if (options_.width < 200 || options_.height < 150)
    throw ovton::core::UsageError("plot: image must be at least 200 x 150 px");
  check_range(options_.x_range, "x");
  check_range(options_.y_range, "y");
}

cv::Scalar Plot::next_auto_color() {
  return palette_color(auto_colors_++);
}

Plot &Plot::add(Series series) {
  if (series.x.size() != series.y.size())
    throw ovton::core::UsageError("plot: series '" + series.name + "' has " + std::to_string(series.x.size()) +
                                  " x but " + std::to_string(series.y.size()) + " y values");
  if (!series.color)
    series.color = next_auto_color();
  series_.push_back(std::move(series));
  return *this;
}

Plot &Plot::add_hline(double y, const std::string &label, std::optional<cv::Scalar> color) {
  return add_line(0.0, y, label, std::move(color));
}

Plot &Plot::add_line(double slope, double intercept, const std::string &label, std::optional<cv::Scalar> color) {
  lines_.push_back({slope, intercept, label, color ? *color : next_auto_color()});
  return *this;
}

PlotFrame Plot::frame_with_left_margin(int left) const {
  PlotFrame f;
  const int top = options_.title.empty() ? 20 : 46, bottom = options_.xlabel.empty() ? 36 : 60, right = 24;
  f.area =
      cv::Rect(left, top, std::max(20, options_.width - left - right), std::max(20, options_.height - top - bottom));

  // Data span over drawable points; a horizontal reference line counts for y, a sloped one is drawn where it falls.
  double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
  for (const Series &s : series_)
    for (size_t i = 0; i < s.x.size(); ++i)
      if (finite(s.x[i], s.y[i]))
        xlo = std::min(xlo, s.x[i]), xhi = std::max(xhi, s.x[i]), ylo = std::min(ylo, s.y[i]),
        yhi = std::max(yhi, s.y[i]);
  for (const RefLine &l : lines_)
    if (l.slope == 0 && std::isfinite(l.intercept))
      ylo = std::min(ylo, l.intercept), yhi = std::max(yhi, l.intercept);
  auto settle = [](double &lo, double &hi) {
    if (!(lo <= hi))
      lo = 0, hi = 1; // no data at all
    if (lo == hi) {
      const double h = lo != 0 ? 0.05 * std::abs(lo) : 1.0;
      lo -= h, hi += h;
    }
    const double pad = 0.04 * (hi - lo);
    lo -= pad, hi += pad;
  };
  settle(xlo, xhi);
  settle(ylo, yhi);
  if (options_.x_range)
    xlo = options_.x_range->lo, xhi = options_.x_range->hi;
  if (options_.y_range)
    ylo = options_.y_range->lo, yhi = options_.y_range->hi;

  if (options_.equal_aspect) { // widen the axis with more px per unit about its centre
    const double sx = (f.area.width - 1) / (xhi - xlo), sy = (f.area.height - 1) / (yhi - ylo), s = std::min(sx, sy);
    const double cx = 0.5 * (xlo + xhi), cy = 0.5 * (ylo + yhi);
    const double hx = 0.5 * (f.area.width - 1) / s, hy = 0.5 * (f.area.height - 1) / s;
    if (sx > s)
      xlo = cx - hx, xhi = cx + hx;
    if (sy > s)
      ylo = cy - hy, yhi = cy + hy;
  }
  f.x_lo = xlo, f.x_hi = xhi, f.y_lo = ylo, f.y_hi = yhi;
  return f;
}

PlotFrame Plot::frame() const {
  // The left margin fits the widest y tick label; those labels depend on the frame, hence two passes.
  const PlotFrame first = frame_with_left_margin(70);
  int widest = 0;
  for (const std::string &s : tick_labels(nice_ticks(first.y_lo, first.y_hi, ticks_for(first.area.height, 60))))
    widest = std::max(widest, text_size(s, kTickScale).width);
  const int left = widest + 16 + (options_.ylabel.empty() ? 0 : 28);
  return frame_with_left_margin(std::clamp(left, 40, options_.width / 3));
}

cv::Mat Plot::render() const {
  const PlotFrame f = frame();
  cv::Mat img(options_.height, options_.width, CV_8UC3, kWhite);
  const cv::Rect &a = f.area;
  const std::vector<double> yt = nice_ticks(f.y_lo, f.y_hi, ticks_for(a.height, 60));
  const std::vector<std::string> yl = tick_labels(yt);
  std::vector<double> xt;
  std::vector<std::string> xl;
  for (int n = ticks_for(a.width, 100); n >= 2; --n) { // fewer x ticks until their labels do not collide
    xt = nice_ticks(f.x_lo, f.x_hi, n);
    xl = tick_labels(xt);
    int widest = 0;
    for (const std::string &l : xl)
      widest = std::max(widest, text_size(l, kTickScale).width);
    if (xt.size() < 2 || f.px(xt[1]) - f.px(xt[0]) > widest + 16)
      break;
  }

  // Grid, tick marks and tick labels.
  const int bottom = a.y + a.height - 1, right = a.x + a.width - 1;
  for (size_t i = 0; i < xt.size(); ++i) {
    const int x = int(std::lround(f.px(xt[i])));
    cv::line(img, {x, a.y}, {x, bottom}, kGrid, 1);
    cv::line(img, {x, bottom}, {x, bottom + 5}, kInk, 1);
    const cv::Size ts = text_size(xl[i], kTickScale);
    text(img, xl[i], {std::min(x - ts.width / 2, options_.width - 2 - ts.width), bottom + 8 + ts.height}, kTickScale);
  }
  for (size_t i = 0; i < yt.size(); ++i) {
    const int y = int(std::lround(f.py(yt[i])));
    cv::line(img, {a.x, y}, {right, y}, kGrid, 1);
    cv::line(img, {a.x - 5, y}, {a.x, y}, kInk, 1);
    const cv::Size ts = text_size(yl[i], kTickScale);
    text(img, yl[i], {a.x - 8 - ts.width, y + ts.height / 2 - 2}, kTickScale);
  }

  // Data, drawn in ROI coordinates so that everything is clipped to the plot area.
  cv::Mat roi = img(a);
  auto rx = [&](double x) { return f.px(x) - a.x; };
  auto ry = [&](double y) { return f.py(y) - a.y; };
  for (const RefLine &l : lines_)
    if (std::isfinite(l.slope) && std::isfinite(l.intercept))
      segment(roi, rx(f.x_lo), ry(l.intercept + l.slope * f.x_lo), rx(f.x_hi), ry(l.intercept + l.slope * f.x_hi),
              l.color, 1, true);
  for (const Series &s : series_) {
    const int thick = thickness(s.width);
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!finite(s.x[i], s.y[i]))
        continue;
      const double x = rx(s.x[i]), y = ry(s.y[i]);
      if (s.style == Series::Style::Points) {
        const double r = std::max(1.0, s.width);
        if (x > -r && y > -r && x < roi.cols + r && y < roi.rows + r)
          cv::circle(roi, fixed(x, y), int(std::lround(r * kOne)), *s.color, cv::FILLED, cv::LINE_AA, kShift);
      } else if (i + 1 < s.x.size() && finite(s.x[i + 1], s.y[i + 1])) {
        segment(roi, x, y, rx(s.x[i + 1]), ry(s.y[i + 1]), *s.color, thick, false);
      } else if ((i == 0 || !finite(s.x[i - 1], s.y[i - 1])) && x >= 0 && y >= 0 && x < roi.cols && y < roi.rows) {
        cv::circle(roi, fixed(x, y), int(std::lround(thick * kOne)), *s.color, cv::FILLED, cv::LINE_AA, kShift);
      } // an isolated point of a line would otherwise vanish
    }
  }
  cv::rectangle(img, a, kInk, 1);

  // Axis labels and title.
  if (!options_.xlabel.empty()) {
    const cv::Size ts = text_size(options_.xlabel, kLabelScale);
    text(img, options_.xlabel, {a.x + a.width / 2 - ts.width / 2, options_.height - 12}, kLabelScale);
  }
  if (!options_.ylabel.empty()) { // OpenCV has no rotated text: draw it flat, rotate, darken into place
    const cv::Size ts = text_size(options_.ylabel, kLabelScale);
    cv::Mat flat(ts.height + 4, ts.width + 4, CV_8UC3, kWhite), up;
    text(flat, options_.ylabel, {2, ts.height - 2}, kLabelScale);
    cv::rotate(flat, up, cv::ROTATE_90_COUNTERCLOCKWISE);
    const cv::Rect dst =
        cv::Rect(6, a.y + a.height / 2 - up.rows / 2, up.cols, up.rows) & cv::Rect(0, 0, img.cols, img.rows);
    if (dst.area() > 0) {
      cv::Mat target = img(dst);
      cv::min(target, up(cv::Rect(0, 0, dst.width, dst.height)), target);
    }
  }
  if (!options_.title.empty()) {
    const cv::Size ts = text_size(options_.title, kTitleScale);
    cv::putText(img, options_.title, {a.x + a.width / 2 - ts.width / 2, 14 + ts.height}, kFont, kTitleScale, kInk, 2,
                cv::LINE_AA);
  }

  // Legend, top right inside the plot area: named series, then named reference lines.
  struct Entry {
    std::string name;
    cv::Scalar color;
    bool points, dashed;
  };
  std::vector<Entry> entries;
  for (const Series &s : series_)
    if (!s.name.empty())
      entries.push_back({s.name, *s.color, s.style == Series::Style::Points, false});
  for (const RefLine &l : lines_)
    if (!l.label.empty())
      entries.push_back({l.label, l.color, false, true});
  if (options_.legend && !entries.empty()) {
    int w = 0;
    for (const Entry &e : entries)
      w = std::max(w, text_size(e.name, kTickScale).width);
    const int row = 20, sample = 26, pad = 8;
    const cv::Size bs(w + sample + 3 * pad, int(entries.size()) * row + pad);
    // The corner that hides the fewest data points (top right on a tie), as matplotlib's loc="best" does.
    cv::Rect box;
    size_t fewest = SIZE_MAX;
    for (const cv::Point &corner :
         {cv::Point(right - 8 - bs.width, a.y + 8), cv::Point(a.x + 8, a.y + 8),
          cv::Point(right - 8 - bs.width, bottom - 8 - bs.height), cv::Point(a.x + 8, bottom - 8 - bs.height)}) {
      const cv::Rect cand(corner, bs);
      size_t hidden = 0;
      for (const Series &s : series_)
        for (size_t i = 0; i < s.x.size(); ++i) {
          if (!finite(s.x[i], s.y[i]))
            continue;
          double ax = f.px(s.x[i]), ay = f.py(s.y[i]), bx = ax, by = ay; // a point, or the segment to the next one
          if (s.style == Series::Style::Line && i + 1 < s.x.size() && finite(s.x[i + 1], s.y[i + 1]))
            bx = f.px(s.x[i + 1]), by = f.py(s.y[i + 1]);
          hidden += clip(ax, ay, bx, by, cand.x, cand.y, cand.x + cand.width, cand.y + cand.height);
        }
      if (hidden < fewest)
        fewest = hidden, box = cand;
    }
    cv::rectangle(img, box, kWhite, cv::FILLED);
    cv::rectangle(img, box, kBorder, 1);
    for (size_t i = 0; i < entries.size(); ++i) {
      const Entry &e = entries[i];
      const int y = box.y + pad / 2 + int(i) * row + row / 2, x0 = box.x + pad;
      if (e.points)
        cv::circle(img, {x0 + sample / 2, y}, 4, e.color, cv::FILLED, cv::LINE_AA);
      else
        segment(img, x0, y, x0 + sample, y, e.color, 2, e.dashed);
      text(img, e.name, {x0 + sample + pad, y + 5}, kTickScale);
    }
  }
  return img;
}

void Plot::save_png(const std::string &file) const {
  std::vector<uchar> bytes;
  if (!ovton::core::encode_image(".png", render(), bytes))
    throw ovton::core::DataError(file, "cannot encode the chart as PNG");
  std::ofstream out(file, std::ios::binary);
  if (!out)
    throw ovton::core::DataError(file, "cannot open for writing");
  out.write(reinterpret_cast<const char *>(bytes.data()), std::streamsize(bytes.size()));
  out.close();
  if (!out)
    throw ovton::core::DataError(file, "write failed");
}

} // namespace ovton::eval
