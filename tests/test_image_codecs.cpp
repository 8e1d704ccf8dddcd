// The image codecs the binary loads on demand (ov_core/io/image_codecs.h): every path gives what OpenCV's own
// imread/imwrite/imencode give, through the plugin, for the files the fast PNG decoder refuses.
#include "ov_core/io/image_codecs.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>

namespace {

cv::Mat colour_pattern() {
  cv::Mat img(37, 53, CV_8UC3);
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x)
      img.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<uchar>(5 * x), static_cast<uchar>(7 * y), static_cast<uchar>((x * y) % 251));
  return img;
}

bool same(const cv::Mat &a, const cv::Mat &b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

std::string temp_file(const std::string &name) {
  return (std::filesystem::temp_directory_path() / ("ovton_codecs_" + name)).string();
}

} // namespace

TEST(ImageCodecs, FilesTheFastDecoderRefusesReadAsOpenCvReadsThem) {
  const cv::Mat colour = colour_pattern();
  cv::Mat gray16;
  cv::cvtColor(colour, gray16, cv::COLOR_BGR2GRAY);
  gray16.convertTo(gray16, CV_16U, 257.0);
  // A colour PNG, a 16-bit gray PNG and a JPEG: none is an 8-bit gray PNG.
  for (const auto &[name, img] :
       {std::pair<std::string, cv::Mat>{"colour.png", colour}, {"gray16.png", gray16}, {"colour.jpg", colour}}) {
    const std::string file = temp_file(name);
    ASSERT_TRUE(cv::imwrite(file, img));
    const cv::Mat gray = ovton::core::read_gray_image(file);
    EXPECT_TRUE(same(gray, cv::imread(file, cv::IMREAD_GRAYSCALE))) << name;
    EXPECT_EQ(gray.type(), CV_8UC1) << name;
    EXPECT_TRUE(same(ovton::core::read_color_image(file), cv::imread(file, cv::IMREAD_COLOR))) << name;
    std::filesystem::remove(file);
  }
  EXPECT_TRUE(ovton::core::read_gray_image(temp_file("no_such_file.png")).empty());
  EXPECT_TRUE(ovton::core::read_color_image(temp_file("no_such_file.png")).empty());
}

TEST(ImageCodecs, WritesAndEncodesAsOpenCvDoes) {
  const cv::Mat colour = colour_pattern();
  const std::vector<int> params = {ovton::core::png_compression_param(), 3};
  EXPECT_EQ(params[0], cv::IMWRITE_PNG_COMPRESSION);
  const std::string file = temp_file("written.png");
  ASSERT_TRUE(ovton::core::write_image(file, colour, params));
  EXPECT_TRUE(same(cv::imread(file, cv::IMREAD_COLOR), colour));
  std::filesystem::remove(file);

  std::vector<uchar> ours, theirs;
  ASSERT_TRUE(ovton::core::encode_image(".png", colour, ours, params));
  ASSERT_TRUE(cv::imencode(".png", colour, theirs, params));
  EXPECT_EQ(ours, theirs);
  // An 8-bit gray PNG comes back through the fast decoder, pixel for pixel.
  cv::Mat gray;
  cv::cvtColor(colour, gray, cv::COLOR_BGR2GRAY);
  ASSERT_TRUE(ovton::core::write_image(file, gray));
  EXPECT_TRUE(same(ovton::core::read_gray_image(file), gray));
  std::filesystem::remove(file);
  EXPECT_FALSE(ovton::core::write_image(temp_file("no_such_folder/x.png"), gray));
}
