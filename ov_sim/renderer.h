#pragma once
// Per-pixel ray caster: distorted pixel -> precomputed camera ray -> first scene face -> mip-mapped texture.
#include "ov_core/cam/camera_model.h"
#include "ov_sim/frame_pose.h"
#include "ov_sim/scene.h"
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

namespace ovton::sim {

struct RenderOptions {
  double noise_sigma = 1.5; ///< grey-level sensor noise (approximately Gaussian, from a per-pixel hash)
  /// Blur bias in mip levels: > 0 softer, < 0 sharper. 0 samples the level whose texel matches the pixel.
  double lod_bias = 0.0;
};

class Renderer {
public:
  /// The scene must outlive the renderer (markers planted later are picked up at the next render).
  Renderer(const ovton::core::CameraModel &cam, const Scene &scene, const RenderOptions &opt = {});

  /// Renders the view of a camera at pose (R_WC, p_WC) into an 8-bit image of the camera's size.
  /// noise_seed selects the sensor-noise pattern (use e.g. the frame index): same inputs, same pixels.
  void render(const Eigen::Matrix3d &R_WC, const Eigen::Vector3d &p_WC, uint64_t noise_seed, cv::Mat &out) const;
  /// Same with a rolling shutter when pose.at_row is set: pixel row v is drawn from the pose at_row(v).
  void render(const FramePose &pose, uint64_t noise_seed, cv::Mat &out) const;

  /// Adds weight x the view's radiance to `acc` (CV_32F, the camera's size): the grey level the scene shows before
  /// any camera effect (texture x face shade, no noise, no rounding). Summing sub-frame poses with weights 1/N
  /// integrates the scene over an exposure (motion blur, camera_effects.h).
  void accumulate(const FramePose &pose, float weight, cv::Mat &acc) const;

private:
  /// Rows [v_begin, v_end) of the view from (R_WC, p_WC); `out` already has the camera's size.
  void render_rows(const Eigen::Matrix3d &R_WC, const Eigen::Vector3d &p_WC, int v_begin, int v_end,
                   uint64_t noise_seed, cv::Mat &out) const;
  /// The ray caster: calls sink(u, v, value) for every pixel of rows [v_begin, v_end) seen from (R_WC, p_WC).
  template <typename Sink>
  void cast_rows(const Eigen::Matrix3d &R_WC, const Eigen::Vector3d &p_WC, int v_begin, int v_end, Sink &&sink) const;
  struct Ray {
    float x, y, z;  ///< unit ray in the camera frame
    float xn, yn;   ///< undistorted normalised coordinates (x/z, y/z), for box culling
    float log2_pix; ///< log2 of the pixel's angular size [rad]
  };
  const ovton::core::CameraModel &cam_;
  const Scene &scene_;
  RenderOptions opt_;
  std::vector<Ray> rays_;
  std::vector<float> row_yn_lo_, row_yn_hi_; ///< per image row, the range of its rays' yn (row culling of boxes)
};

} // namespace ovton::sim
