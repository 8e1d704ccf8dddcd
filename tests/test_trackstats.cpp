// ov_eval/trackstats: the KLT check counts what it should on images whose answer is known, and the image statistics
// (plain-pixel share, noise estimate) measure what they claim.
#include "ov_core/types/errors.h"
#include "ov_eval/trackstats.h"
#include "test_util.h"

#include <opencv2/imgproc.hpp>

using ovton::eval::gradient_stats;
using ovton::eval::track_statistics;

namespace {

/// A blotchy 8-bit texture (smoothed noise): corners everywhere, nothing repetitive.
cv::Mat texture(int w, int h, int seed) {
  cv::Mat n(h, w, CV_32F);
  cv::RNG rng(seed);
  rng.fill(n, cv::RNG::UNIFORM, 0.0, 255.0);
  cv::GaussianBlur(n, n, cv::Size(0, 0), 3.0);
  cv::normalize(n, n, 0, 255, cv::NORM_MINMAX);
  cv::Mat out;
  n.convertTo(out, CV_8U);
  return out;
}

} // namespace

TEST(TrackStats, SteadyPanKeepsEveryTrackAndDetectsOnlyWhatLeaves) {
  const cv::Mat big = texture(900, 500, 7);
  std::vector<std::pair<int64_t, cv::Mat>> frames;
  const int n = 30;
  for (int k = 0; k < n; ++k) // the view pans 2 px per frame to the right over the texture
    frames.emplace_back(1000000000LL + k * 50000000LL, big(cv::Rect(2 * k, 10, 752, 480)).clone());
  const auto r = track_statistics(frames);
  const auto &s = r.summary;
  std::cout << "[ measured ] pan: tracked median " << s.tracked_median << ", new share " << s.new_share_mean
            << ", track median " << s.track_length_median << ", fb median " << s.fb_median_px << " px\n";
  EXPECT_EQ(s.frames, static_cast<size_t>(n));
  EXPECT_EQ(r.frames.front().new_share, 1.0);
  EXPECT_GE(s.tracked_median, 190.0);
  // 2 px per frame leave the image: few points are lost, far fewer than 1 in 20 per frame.
  EXPECT_LT(s.new_share_mean, 0.02);
  // Most tracks live through the whole sequence (censored at its end).
  EXPECT_GE(s.track_length_median, n - 1);
  EXPECT_LT(s.fb_median_px, 0.05);
}

TEST(TrackStats, NewImagesEveryFrameMeanEverythingIsNew) {
  std::vector<std::pair<int64_t, cv::Mat>> frames;
  for (int k = 0; k < 6; ++k)
    frames.emplace_back(k, texture(752, 480, 100 + k)); // unrelated images: nothing can be tracked
  const auto r = track_statistics(frames);
  EXPECT_GT(r.summary.new_share_mean, 0.9);
  // A forward-backward check still lets a few chance matches through on smooth, unrelated textures.
  EXPECT_LT(r.summary.tracks, 0.1 * 5 * 200);
}

TEST(TrackStats, SpanAndOptionsAreChecked) {
  std::vector<std::pair<int64_t, cv::Mat>> frames = {{0, texture(100, 100, 1)}, {10, texture(100, 100, 1)}};
  ovton::eval::TrackStatsOptions o;
  o.t_begin_ns = 5;
  EXPECT_THROW(track_statistics(frames, o), ovton::core::UsageError); // one image left
  o = {};
  o.win_size = 1;
  EXPECT_THROW(track_statistics(frames, o), ovton::core::UsageError);
  std::vector<std::pair<int64_t, std::string>> files = {{0, "/no/such.png"}, {1, "/no/such2.png"}};
  EXPECT_THROW(track_statistics(files), ovton::core::DataError);
}

TEST(TrackStats, GradientAndNoiseStatistics) {
  const cv::Mat flat(480, 752, CV_8U, cv::Scalar(120));
  const auto g0 = gradient_stats(flat);
  EXPECT_EQ(g0.low_share, 1.0);
  EXPECT_NEAR(g0.noise_sigma, 0.0, 1e-9);
  // Gaussian noise of sigma 4 on a flat grey: the estimate finds it, and a Sobel of such noise (sigma 4 sqrt(12) per
  // direction, Rayleigh magnitude) stays below 20 for 1 - exp(-20^2 / (2 * 192)) = 65 % of the pixels.
  cv::Mat noisy(480, 752, CV_32F);
  cv::RNG rng(3);
  rng.fill(noisy, cv::RNG::NORMAL, 120.0, 4.0);
  cv::Mat n8;
  noisy.convertTo(n8, CV_8U);
  const auto g = gradient_stats(n8);
  std::cout << "[ measured ] noise sigma 4: estimated " << g.noise_sigma << ", plain share " << g.low_share << "\n";
  EXPECT_NEAR(g.noise_sigma, 4.0, 0.3);
  EXPECT_NEAR(g.low_share, 0.65, 0.03);
}
