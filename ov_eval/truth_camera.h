#pragma once
// The ground-truth camera pose at the instant an image shows (its stamp + the true t_d): what the evaluation of a
// front end's tracks (track_truth) and of image velocities (velocity_truth) measures against.
#include "ov_core/io/dataset.h"

#include <Eigen/Core>
#include <cstdint>

namespace ovton::eval {

struct CameraPose {
  Eigen::Matrix3d R_WC;
  Eigen::Vector3d p_WC;
};

class TruthCamera {
public:
  /// `d` must outlive this object and hold a ground truth with orientations.
  explicit TruthCamera(const ovton::core::Dataset &d);
  /// IMU-clock time the image stamped t_cam shows: the dataset's t_d truth, else its prior.
  int64_t t_imu(int64_t t_cam_ns) const;
  /// Camera pose at IMU time t; false outside the ground truth.
  bool at_imu(int64_t t_imu_ns, CameraPose &c) const;
  /// Camera pose at the instant the image stamped t_cam shows.
  bool at_image(int64_t t_cam_ns, CameraPose &c) const { return at_imu(t_imu(t_cam_ns), c); }

private:
  const ovton::core::Dataset &d_;
  Eigen::Matrix3d R_BC_;
  Eigen::Vector3d p_BC_;
};

} // namespace ovton::eval
