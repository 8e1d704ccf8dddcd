#pragma once
// Synthetic images for the KLT tests: EuRoC's camera without distortion and a smooth random texture.
#include "ov_core/cam/camera_calib.h"
#include "ov_sim/euroc_calib.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdint>

namespace ovtest {

constexpr int kTrackW = 752, kTrackH = 480;

/// EuRoC cam0 intrinsics without distortion, so that an image-space shift is the same shift in normalised units.
inline ovton::core::CameraCalib pinhole_calib() {
  ovton::core::CameraCalib c;
  c.width = kTrackW;
  c.height = kTrackH;
  c.rate_hz = 20;
  c.intrinsics = ovton::sim::euroc_cam0_calib().intrinsics;
  c.dist_coeffs.setZero();
  return c;
}

/// Smooth random texture (blobs a few pixels wide): corners everywhere, and smooth enough for sub-pixel LK.
inline cv::Mat random_texture(int w, int h, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat small(h / 4 + 1, w / 4 + 1, CV_8UC1);
  rng.fill(small, cv::RNG::UNIFORM, 0, 256);
  cv::Mat big;
  cv::resize(small, big, cv::Size(w, h), 0, 0, cv::INTER_CUBIC);
  cv::GaussianBlur(big, big, cv::Size(0, 0), 1.0);
  return big;
}

} // namespace ovtest
