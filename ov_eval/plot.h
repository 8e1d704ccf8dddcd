#pragma once
// PNG charts drawn with OpenCV alone, so that `ovton compare` and `ovton diagnose` can draw their figures on a bare
// machine that has the product's own dependencies and nothing else (no Python, no matplotlib).
#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace ovton::eval {

/// One data set on a chart. Points with a NaN or infinite coordinate are skipped, and a line breaks at them.
struct Series {
  enum class Style { Line, Points };
  Series() = default;
  Series(std::string name_, std::vector<double> x_, std::vector<double> y_, Style style_ = Style::Line)
      : name(std::move(name_)), x(std::move(x_)), y(std::move(y_)), style(style_) {}

  std::string name; ///< legend text; an empty name keeps the series out of the legend
  std::vector<double> x, y;
  Style style = Style::Line;
  std::optional<cv::Scalar> color; ///< BGR; unset: the next colour of palette_color()
  double width = 1.5;              ///< line thickness in px (rounded, at least 1), or marker radius for Points
};

struct AxisRange {
  double lo, hi;
};

struct PlotOptions {
  std::string title, xlabel, ylabel;
  int width = 1000, height = 600; ///< image size in px
  bool equal_aspect = false;      ///< equal px per unit on both axes (top views); widens one axis' range to do so
  bool legend = true;
  std::optional<AxisRange> x_range, y_range; ///< fixed ranges; unset: the data's span plus a small margin
};

/// "Nice" tick values (1, 2 or 5 times a power of ten) inside [lo, hi], at most max_ticks of them, each an exact
/// integer multiple of the step (so 0 is exactly 0). Throws UsageError unless lo < hi are finite and max_ticks >= 2.
std::vector<double> nice_ticks(double lo, double hi, int max_ticks = 8);

/// Colour i of a fixed palette of 8 distinguishable colours (matplotlib's tab10 without grey and olive), BGR.
cv::Scalar palette_color(size_t i);

/// Where the data lands in the image: the plot area and the axis ranges it shows. Pixel coordinates are those of
/// OpenCV (integer = pixel centre, y down); x_lo maps to the area's left column, y_lo to its bottom row.
struct PlotFrame {
  cv::Rect area;
  double x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;
  double px(double x) const { return area.x + (x - x_lo) / (x_hi - x_lo) * (area.width - 1); }
  double py(double y) const { return area.y + (area.height - 1) - (y - y_lo) / (y_hi - y_lo) * (area.height - 1); }
};

/// A 2-D chart: white background, grid at nice ticks, axis labels, title, legend, anti-aliased lines.
/// Rendering is a pure function of the inputs, so the same plot gives the same PNG bytes.
class Plot {
public:
  /// Throws UsageError for an image smaller than 200 x 150 px or an empty / non-finite fixed range.
  explicit Plot(PlotOptions options = {});

  /// Throws UsageError when x and y differ in length.
  Plot &add(Series series);
  /// A dashed reference line y = value across the whole plot (e.g. the true time offset).
  Plot &add_hline(double y, const std::string &label = "", std::optional<cv::Scalar> color = {});
  /// A dashed line y = intercept + slope * x across the whole plot (e.g. a fit over a scatter).
  Plot &add_line(double slope, double intercept, const std::string &label = "", std::optional<cv::Scalar> color = {});

  PlotFrame frame() const;
  cv::Mat render() const; ///< CV_8UC3, BGR
  /// Writes PNG bytes whatever the file's extension; throws DataError naming the file if it cannot be written.
  void save_png(const std::string &file) const;

private:
  struct RefLine {
    double slope, intercept;
    std::string label;
    cv::Scalar color;
  };
  PlotFrame frame_with_left_margin(int left) const;
  cv::Scalar next_auto_color();

  PlotOptions options_;
  std::vector<Series> series_; // colours resolved on add(), so the palette order is the order of addition
  std::vector<RefLine> lines_;
  size_t auto_colors_ = 0;
};

} // namespace ovton::eval
