#pragma once
// The camera's pose over one frame's exposure, shared by the feature simulator and the renderer.
#include <Eigen/Core>
#include <functional>

namespace ovton::sim {

/// A global shutter sees the whole image from (R_WC, p_WC); a rolling shutter (at_row set) sees each image row from
/// its own pose, at_row(v) for the (continuous, distorted-pixel) row v. (R_WC, p_WC) is then row 0's pose.
struct FramePose {
  Eigen::Matrix3d R_WC = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_WC = Eigen::Vector3d::Zero();
  std::function<void(double row, Eigen::Matrix3d &R_WC, Eigen::Vector3d &p_WC)> at_row; ///< empty: global shutter
};

} // namespace ovton::sim
