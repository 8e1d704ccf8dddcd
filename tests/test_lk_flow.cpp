// ov_core/track/lk_flow: the vectorised Lucas-Kanade against OpenCV's cv::calcOpticalFlowPyrLK, the algorithm it
// reimplements, on real EuRoC flight images (and on a synthetic shift where ../shared is absent), and against a
// known sub-pixel motion.
#include "ov_core/track/lk_flow.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <filesystem>
#include <random>

namespace {

constexpr int kWin = 21, kLevels = 3;

cv::Mat textured(int w, int h, unsigned seed) {
  cv::Mat noise(h / 4, w / 4, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
  cv::Mat img;
  cv::resize(noise, img, cv::Size(w, h), 0, 0, cv::INTER_CUBIC);
  cv::GaussianBlur(img, img, cv::Size(5, 5), 1.2);
  return img;
}

/// Corners of `img` as OpenCV's FAST finds them, strongest first, at most n.
std::vector<cv::Point2f> corners(const cv::Mat &img, size_t n) {
  std::vector<cv::KeyPoint> kp;
  cv::FAST(img, kp, 20, true);
  std::sort(kp.begin(), kp.end(), [](const auto &a, const auto &b) { return a.response > b.response; });
  std::vector<cv::Point2f> pts;
  for (size_t i = 0; i < kp.size() && pts.size() < n; ++i)
    pts.push_back(kp[i].pt);
  return pts;
}

struct Comparison {
  size_t both = 0, disagree_status = 0;
  std::vector<double> dist;
};

/// OpenCV's pyramids of a and b and lk_flow's made from them.
struct Pyramids {
  std::vector<cv::Mat> pa, pb;
  ovton::core::LkPyramid la, lb;
  Pyramids(const cv::Mat &a, const cv::Mat &b) {
    cv::buildOpticalFlowPyramid(a, pa, cv::Size(kWin, kWin), kLevels, false);
    cv::buildOpticalFlowPyramid(b, pb, cv::Size(kWin, kWin), kLevels, false);
    la.build(pa, kWin);
    lb.build(pb, kWin);
  }
};

/// Tracks `pts` from a to b with both implementations (the same options) and compares their answers.
Comparison compare(const cv::Mat &a, const cv::Mat &b, const std::vector<cv::Point2f> &pts) {
  const Pyramids py(a, b);
  const auto &[pa, pb, la, lb] = py;
  ovton::core::LkParams p;
  p.win = kWin;
  p.max_level = kLevels;
  std::vector<cv::Point2f> ours, theirs;
  std::vector<unsigned char> st_ours, st_theirs;
  ovton::core::lk_flow(la, lb, pts, ours, st_ours, p);
  cv::calcOpticalFlowPyrLK(pa, pb, pts, theirs, st_theirs, cv::noArray(), cv::Size(kWin, kWin), kLevels,
                           cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, p.max_iter, p.eps));
  Comparison c;
  for (size_t i = 0; i < pts.size(); ++i) {
    if (st_ours[i] != st_theirs[i])
      ++c.disagree_status;
    if (st_ours[i] && st_theirs[i]) {
      ++c.both;
      c.dist.push_back(cv::norm(ours[i] - theirs[i]));
    }
  }
  std::sort(c.dist.begin(), c.dist.end());
  return c;
}

double quantile(const std::vector<double> &v, double q) {
  return v.empty() ? 0 : v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))];
}

} // namespace

TEST(LkFlow, AgreesWithOpenCvOnRealFlightImages) {
  OVTEST_REQUIRE_SHARED_DATA();
  std::vector<std::filesystem::path> files;
  for (const auto &e :
       std::filesystem::directory_iterator(ovtest::shared_data() + "/euroc_v1_01_moving/mav0/cam0/data"))
    files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 60u);
  Comparison all;
  // Consecutive images (the tracker's case) and images 3 apart (motion up to tens of pixels: the pyramid's levels).
  for (size_t k = 0; k + 3 < 60; k += 6)
    for (size_t gap : {1, 3}) {
      const cv::Mat a = cv::imread(files[k].string(), cv::IMREAD_GRAYSCALE);
      const cv::Mat b = cv::imread(files[k + gap].string(), cv::IMREAD_GRAYSCALE);
      const Comparison c = compare(a, b, corners(a, 200));
      all.both += c.both;
      all.disagree_status += c.disagree_status;
      all.dist.insert(all.dist.end(), c.dist.begin(), c.dist.end());
    }
  std::sort(all.dist.begin(), all.dist.end());
  const size_t total = all.both + all.disagree_status;
  ASSERT_GT(all.both, 3000u);
  // Where OpenCV finds a point ours finds it too, and vice versa, but for a handful on the edge of the eigenvalue
  // test or the image border; where both find it, the same place to a thousandth of a pixel.
  EXPECT_LT(static_cast<double>(all.disagree_status), 0.01 * static_cast<double>(total));
  // (Measured: median and 99 % 0.0001 px. A Scharr weight of 9 instead of 10 in y alone gives 0.0005 / 0.0021 / 0.0040
  // px at the median / 95 % / 99 %: these bounds catch it.)
  EXPECT_LT(quantile(all.dist, 0.5), 0.001);
  EXPECT_LT(quantile(all.dist, 0.95), 0.001);
  EXPECT_LT(quantile(all.dist, 0.99), 0.01);
  std::printf("[ lk_flow  ] %zu points: status differs on %zu; |ours - OpenCV| median %.4f, 95 %% %.4f, 99 %% %.4f, "
              "max %.3f px\n",
              all.both, all.disagree_status, quantile(all.dist, 0.5), quantile(all.dist, 0.95),
              quantile(all.dist, 0.99), all.dist.back());
}

TEST(LkFlow, FindsAKnownSubPixelShiftAsOpenCvDoes) {
  // A texture moved by (3.3, -1.7) px: both implementations find the motion, and each other's answers.
  const cv::Mat a = textured(320, 240, 7);
  cv::Mat b;
  const cv::Matx23f shift(1, 0, 3.3f, 0, 1, -1.7f);
  cv::warpAffine(a, b, shift, a.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT_101);
  std::vector<cv::Point2f> pts;
  for (int y = 40; y < 200; y += 20)
    for (int x = 40; x < 280; x += 20)
      pts.emplace_back(static_cast<float>(x) + 0.37f, static_cast<float>(y) + 0.81f);
  const Comparison c = compare(a, b, pts);
  EXPECT_EQ(c.disagree_status, 0u);
  EXPECT_EQ(c.both, pts.size());
  EXPECT_LT(quantile(c.dist, 0.99), 0.02);

  const Pyramids py(a, b);
  const ovton::core::LkPyramid &la = py.la, &lb = py.lb;
  std::vector<cv::Point2f> next;
  std::vector<unsigned char> status;
  ovton::core::lk_flow(la, lb, pts, next, status, ovton::core::LkParams{});
  // Within 0.1 px of the true shift: bilinear interpolation of a cubic-resampled texture leaves both implementations
  // up to 0.06 px short in y here (they agree with each other to 0.02 px, above).
  for (size_t i = 0; i < pts.size(); ++i) {
    ASSERT_TRUE(status[i]);
    EXPECT_NEAR(next[i].x - pts[i].x, 3.3, 0.1) << i;
    EXPECT_NEAR(next[i].y - pts[i].y, -1.7, 0.1) << i;
  }
  // Started from a guess near the answer (the gyro prior's case), the same answer.
  std::vector<cv::Point2f> guess = next, again;
  for (auto &g : guess)
    g += cv::Point2f(0.6f, -0.4f);
  again = guess;
  ovton::core::LkParams p;
  p.use_initial = true;
  ovton::core::lk_flow(la, lb, pts, again, status, p);
  for (size_t i = 0; i < pts.size(); ++i)
    EXPECT_LT(cv::norm(again[i] - next[i]), 0.02) << i;
}

TEST(LkFlow, PointsOutsideTheImageAreLost) {
  const cv::Mat a = textured(160, 120, 3);
  std::vector<cv::Mat> pa;
  cv::buildOpticalFlowPyramid(a, pa, cv::Size(kWin, kWin), 2, false);
  ovton::core::LkPyramid la;
  la.build(pa, kWin);
  const std::vector<cv::Point2f> pts = {{80, 60}, {-40, 60}, {80, 500}, {159.9f, 119.9f}};
  std::vector<cv::Point2f> next;
  std::vector<unsigned char> status;
  ovton::core::lk_flow(la, la, pts, next, status, ovton::core::LkParams{});
  EXPECT_TRUE(status[0]);
  EXPECT_LT(cv::norm(next[0] - pts[0]), 1e-3);
  EXPECT_FALSE(status[1]);
  EXPECT_FALSE(status[2]);
  // A window larger than the pyramid's border, and a pyramid built without its padding, are refused, not read out
  // of bounds.
  ovton::core::LkParams wide;
  wide.win = kWin + 2;
  EXPECT_THROW(ovton::core::lk_flow(la, la, pts, next, status, wide), ovton::core::UsageError);
  cv::Mat bare = a.clone();
  EXPECT_THROW(la.build({bare}, kWin), ovton::core::UsageError);
}
