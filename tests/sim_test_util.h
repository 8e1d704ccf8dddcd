#pragma once
// Helpers shared by the simulator tests (test_sim_*.cpp).
#include "ov_core/cam/camera_model.h"
#include "ov_sim/feature_sim.h"
#include "ov_sim/renderer.h"
#include "ov_sim/scene.h"
#include "ov_sim/simulator.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <algorithm>
#include <memory>
#include <vector>

namespace ovtest {

inline double median(std::vector<double> v) {
  if (v.empty())
    return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

/// Darkness-weighted centroid inside a disc of radius r around c (a planted marker's dark core on a white ring).
inline Eigen::Vector2d dark_centroid(const cv::Mat &img, const Eigen::Vector2d &c, double r) {
  double sw = 0, su = 0, sv = 0;
  for (int v = static_cast<int>(c.y() - r - 1); v <= static_cast<int>(c.y() + r + 1); ++v)
    for (int u = static_cast<int>(c.x() - r - 1); u <= static_cast<int>(c.x() + r + 1); ++u) {
      if (u < 0 || v < 0 || u >= img.cols || v >= img.rows || (Eigen::Vector2d(u, v) - c).norm() > r)
        continue;
      const double w = std::max(0.0, 200.0 - img.at<uint8_t>(v, u));
      sw += w;
      su += w * u;
      sv += w * v;
    }
  return Eigen::Vector2d(su / sw, sv / sw);
}

/// A camera orientation looking along world +x (image x = world −y, image y = world −z).
inline Eigen::Matrix3d look_along_x() {
  Eigen::Matrix3d R;
  R.col(0) = Eigen::Vector3d(0, -1, 0);
  R.col(1) = Eigen::Vector3d(0, 0, -1);
  R.col(2) = Eigen::Vector3d(1, 0, 0);
  return R;
}

/// An empty 6 x 6 x 3 m room (no boxes) to plant markers in, and noise-free rendering options.
inline ovton::sim::Scene marker_room() {
  ovton::sim::SceneOptions so;
  so.num_boxes = 0;
  so.seed = 5;
  return ovton::sim::Scene(ovton::sim::AlignedBox{Eigen::Vector3d(-3, -3, 0), Eigen::Vector3d(3, 3, 3)}, {}, so);
}
inline ovton::sim::RenderOptions noise_free_rendering() {
  ovton::sim::RenderOptions ro;
  ro.noise_sigma = 0.0;
  return ro;
}

/// The simulator's trajectory, scene and camera for `o`, with a noise-free feature simulator on them (members in
/// construction order: the simulator keeps references to the camera and the scene).
struct NoiseFreeFeatureSim {
  explicit NoiseFreeFeatureSim(const ovton::sim::SimOptions &o)
      : traj(ovton::sim::make_trajectory(o)), scene(ovton::sim::make_scene(*traj, o)), cam(o.cam),
        features(cam, scene, noise_free()) {}
  std::unique_ptr<ovton::sim::Trajectory> traj;
  ovton::sim::Scene scene;
  ovton::core::CameraModel cam;
  ovton::sim::FeatureSimulator features;

private:
  static ovton::sim::FeatureSimOptions noise_free() {
    ovton::sim::FeatureSimOptions fo;
    fo.pixel_noise = 0.0;
    return fo;
  }
};

} // namespace ovtest
