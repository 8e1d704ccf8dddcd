// OpenCV-only PNG charts: nice ticks, the pixel mapping, equal aspect, NaN breaks, errors, determinism.
#include "ov_core/types/errors.h"
#include "ov_eval/plot.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <filesystem>
#include <limits>

using namespace ovton::core;
using namespace ovton::eval;

namespace {

/// Row in column x whose pixel is closest to colour c (and that distance), searched over the plot area.
std::pair<int, double> closest_row(const cv::Mat &img, const cv::Rect &area, int x, const cv::Scalar &c) {
  int best = -1;
  double best_d = 1e9;
  for (int y = area.y + 1; y < area.y + area.height - 1; ++y) {
    const cv::Vec3b &p = img.at<cv::Vec3b>(y, x);
    const double d = std::abs(p[0] - c[0]) + std::abs(p[1] - c[1]) + std::abs(p[2] - c[2]);
    if (d < best_d)
      best_d = d, best = y;
  }
  return {best, best_d};
}

PlotOptions fixed_ranges() {
  PlotOptions o;
  o.x_range = AxisRange{0, 10};
  o.y_range = AxisRange{-1, 1};
  return o;
}

} // namespace

TEST(Plot, NiceTicks) {
  const std::vector<double> t = nice_ticks(0, 7.3, 8);
  ASSERT_EQ(t.size(), 8u);
  for (size_t i = 0; i < t.size(); ++i)
    EXPECT_DOUBLE_EQ(t[i], double(i));
  const std::vector<double> t2 = nice_ticks(0, 7.3, 5);
  EXPECT_EQ(t2, (std::vector<double>{0, 2, 4, 6}));

  const std::vector<double> s = nice_ticks(-0.013, 0.021, 8); // -0.010, -0.005, ..., 0.020
  ASSERT_EQ(s.size(), 7u);
  EXPECT_NEAR(s.front(), -0.010, 1e-15);
  EXPECT_NEAR(s.back(), 0.020, 1e-15);
  EXPECT_EQ(s[2], 0.0); // exactly zero, so the label is "0.000" and not "-0.000"
  for (size_t i = 1; i < s.size(); ++i)
    EXPECT_NEAR(s[i] - s[i - 1], 0.005, 1e-15);

  for (double lo : {-123.4, 0.0, 1e-7, 3e8})
    for (double span : {1e-6, 0.37, 5.0, 1234.5})
      for (int n : {2, 5, 11}) {
        const std::vector<double> v = nice_ticks(lo, lo + span, n);
        ASSERT_GE(v.size(), 1u) << lo << " " << span << " " << n;
        EXPECT_LE(int(v.size()), n);
        EXPECT_GE(v.front(), lo - 1e-9 * span);
        EXPECT_LE(v.back(), lo + span + 1e-9 * span);
      }
  EXPECT_THROW(nice_ticks(1, 1), UsageError);
  EXPECT_THROW(nice_ticks(0, NAN), UsageError);
}

TEST(Plot, HorizontalLineLandsOnMappedRow) {
  for (double level : {0.0, 0.5, -0.73}) {
    Plot p(fixed_ranges());
    p.add({"flat", {0, 10}, {level, level}});
    const PlotFrame f = p.frame();
    EXPECT_DOUBLE_EQ(f.x_lo, 0);
    EXPECT_DOUBLE_EQ(f.y_hi, 1);
    const cv::Mat img = p.render();
    for (double x : {2.3, 5.0, 7.9}) {
      const auto [row, dist] = closest_row(img, f.area, int(std::lround(f.px(x))), palette_color(0));
      EXPECT_LT(dist, 60) << "the series colour is absent at x = " << x;
      EXPECT_NEAR(row, f.py(level), 1.0) << "level " << level << " x " << x;
    }
  }
}

TEST(Plot, EqualAspect) {
  PlotOptions o;
  o.equal_aspect = true;
  Plot p(o);
  p.add({"track", {0, 10, 10, 0}, {0, 0, 1, 1}});
  const PlotFrame f = p.frame();
  const double sx = f.px(1) - f.px(0), sy = f.py(0) - f.py(1);
  EXPECT_NEAR(sx, sy, 1e-9);
  EXPECT_LE(f.x_lo, 0);
  EXPECT_GE(f.x_hi, 10);
  EXPECT_LE(f.y_lo, 0);
  EXPECT_GE(f.y_hi, 1);
  // A wide x span: the y range is what widens, about the data's centre.
  EXPECT_NEAR(0.5 * (f.y_lo + f.y_hi), 0.5, 1e-9);
}

TEST(Plot, NonFiniteBreaksTheLine) {
  Plot p(fixed_ranges());
  std::vector<double> x, y;
  for (int i = 0; i <= 10; ++i)
    x.push_back(i), y.push_back(0.0);
  y[5] = std::numeric_limits<double>::quiet_NaN();
  x[8] = std::numeric_limits<double>::infinity();
  p.add({"gappy", x, y});
  p.add({"wild", {0, 1e300, 2}, {0, -1e300, 0.5}}); // far-off points must not overflow pixel coordinates
  p.add({"empty", {}, {}});
  p.add({"scatter", {1, NAN, 3}, {0.5, 0.5, NAN}, Series::Style::Points});
  const PlotFrame f = p.frame();
  cv::Mat img;
  ASSERT_NO_THROW(img = p.render());
  const cv::Scalar c = palette_color(0);
  auto colour_at = [&](double xv) {
    const cv::Vec3b px = img.at<cv::Vec3b>(int(std::lround(f.py(0))), int(std::lround(f.px(xv))));
    return std::abs(px[0] - c[0]) + std::abs(px[1] - c[1]) + std::abs(px[2] - c[2]) < 60;
  };
  EXPECT_TRUE(colour_at(2.5));
  EXPECT_FALSE(colour_at(4.5)) << "the line must break at the NaN sample";
  EXPECT_FALSE(colour_at(5.5));
  EXPECT_TRUE(colour_at(6.5));
  EXPECT_FALSE(colour_at(7.5)) << "the line must break at the infinite sample";
  EXPECT_TRUE(colour_at(9.5));
}

TEST(Plot, EmptyPlotRenders) {
  Plot p;
  const cv::Mat img = p.render();
  EXPECT_EQ(img.cols, 1000);
  EXPECT_EQ(img.rows, 600);
  EXPECT_EQ(img.type(), CV_8UC3);
}

TEST(Plot, BadInputsThrow) {
  EXPECT_THROW(Plot().add({"x", {1, 2}, {1}}), UsageError);
  PlotOptions o;
  o.y_range = AxisRange{1, 1};
  EXPECT_THROW(Plot{o}, UsageError);
  PlotOptions small;
  small.width = 50;
  EXPECT_THROW(Plot{small}, UsageError);
}

TEST(Plot, SavePngToUnwritablePathThrowsDataError) {
  Plot p;
  p.add({"a", {0, 1}, {0, 1}});
  const std::string bad = "/nonexistent_dir_for_ovton_plot/chart.png";
  try {
    p.save_png(bad);
    FAIL() << "expected DataError";
  } catch (const DataError &e) {
    EXPECT_EQ(e.file(), bad);
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos);
  }
}

TEST(Plot, DeterministicAndReadable) {
  auto make = [] {
    PlotOptions o;
    o.title = "t_d estimate";
    o.xlabel = "time [s]";
    o.ylabel = "t_d [ms]";
    Plot p(o);
    std::vector<double> x, y1, y2;
    for (int i = 0; i < 200; ++i)
      x.push_back(0.1 * i), y1.push_back(5 * std::sin(0.05 * i)), y2.push_back(0.02 * i - 1);
    p.add({"ton", x, y1}).add({"sr", x, y2}).add_hline(3.0, "truth", cv::Scalar(0, 0, 0));
    return p;
  };
  const cv::Mat a = make().render(), b = make().render();
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);

  const std::string file = (std::filesystem::temp_directory_path() / "ovton_test_plot.png").string();
  make().save_png(file);
  const cv::Mat back = cv::imread(file, cv::IMREAD_COLOR);
  std::filesystem::remove(file);
  ASSERT_FALSE(back.empty());
  EXPECT_EQ(cv::norm(a, back, cv::NORM_INF), 0.0); // PNG is lossless
}
