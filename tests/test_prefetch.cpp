// ImagePrefetcher: images decoded on a second thread are the images cv::imread gives, in any order the replay asks
// for them (a filter fed through it: TrackPipeline.FilterGivesTheSameTrajectoryOnAnyThreads).
#include "ov_core/io/image_prefetcher.h"
#include "test_util.h"

#include <opencv2/imgcodecs.hpp>

#include <memory>

using namespace ovton::core;

namespace {

/// n small PNGs whose pixels encode their index; entry `bad` (if < n) names a file that does not exist.
std::vector<ImageEntry> write_images(const ovtest::TempDir &dir, size_t n, size_t bad = SIZE_MAX) {
  std::vector<ImageEntry> images;
  for (size_t i = 0; i < n; ++i) {
    ImageEntry e;
    e.t_cam_ns = static_cast<int64_t>(i) * 50000000;
    e.path = dir / ("img" + std::to_string(i) + ".png");
    if (i != bad)
      cv::imwrite(e.path, cv::Mat(8, 12, CV_8UC1, cv::Scalar(static_cast<double>(i))));
    images.push_back(e);
  }
  return images;
}

int pixel(const cv::Mat &m) {
  return m.empty() ? -1 : m.at<uint8_t>(0, 0);
}

} // namespace

TEST(ImagePrefetcher, GivesEveryImageInOrder) {
  ovtest::TempDir dir;
  const auto images = write_images(dir, 20);
  ImagePrefetcher pf(images, 2);
  for (size_t i = 0; i < images.size(); ++i)
    EXPECT_EQ(pixel(pf.get(i)), static_cast<int>(i));
  EXPECT_TRUE(pf.get(images.size()).empty()); // outside the list
}

TEST(ImagePrefetcher, SkipsAndRevisitsAndReportsUnreadable) {
  ovtest::TempDir dir;
  const auto images = write_images(dir, 30, 7);
  ImagePrefetcher pf(images, 3);
  EXPECT_EQ(pixel(pf.get(0)), 0);
  EXPECT_EQ(pixel(pf.get(5)), 5);   // 1-4 skipped (the replay had no IMU for them)
  EXPECT_EQ(pixel(pf.get(7)), -1);  // missing file: empty, the caller names it
  EXPECT_EQ(pixel(pf.get(3)), 3);   // behind: decoded directly
  EXPECT_EQ(pixel(pf.get(8)), 8);   // and on again
  EXPECT_EQ(pixel(pf.get(29)), 29); // far ahead
}

TEST(ImagePrefetcher, StopsCleanlyWhenDroppedEarly) {
  ovtest::TempDir dir;
  const auto images = write_images(dir, 40);
  for (size_t stop_after : {0u, 1u, 10u}) {
    ImagePrefetcher pf(images, 2);
    for (size_t i = 0; i < stop_after; ++i)
      EXPECT_EQ(pixel(pf.get(i)), static_cast<int>(i));
  } // destructor joins a thread that may be waiting or decoding
}

// Images decoded before the replay (the coarse t_d search's) are handed out as given, not decoded again, on the
// thread and when asked again; the others are decoded.
TEST(ImagePrefetcher, HandsOutGivenImages) {
  ovtest::TempDir dir;
  const auto images = write_images(dir, 12, 9);
  auto given = std::make_shared<DecodedImages>();
  for (size_t i : {2u, 3u, 4u, 9u}) // 9 has no file: only the given image can be handed out
    (*given)[i] = cv::Mat(8, 12, CV_8UC1, cv::Scalar(static_cast<double>(100 + i)));
  ImagePrefetcher pf(images, 2, given);
  for (size_t i = 0; i < images.size(); ++i)
    EXPECT_EQ(pixel(pf.get(i)), given->count(i) ? static_cast<int>(100 + i) : static_cast<int>(i)) << i;
  EXPECT_EQ(pixel(pf.get(3)), 103); // behind: from the given ones again
  EXPECT_EQ(pixel(pf.get(1)), 1);
  EXPECT_EQ(given->at(3).data, pf.get(3).data) << "the pixels are shared, not copied";
}
