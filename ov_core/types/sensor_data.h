#pragma once
// Sensor messages. Every stamp is int64 nanoseconds; the clock is in the name (docs/architecture.md).
#include "ov_core/types/time.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ovton::core {

/// One IMU reading, stamped in the IMU clock. EuRoC order: gyro [rad/s] first, then accel [m/s^2].
struct ImuData {
  int64_t t_imu_ns = 0;
  Eigen::Vector3d wm = Eigen::Vector3d::Zero();
  Eigen::Vector3d am = Eigen::Vector3d::Zero();
};

/// A feature point seen in one frame, as a feature-level dataset (cam0/features.csv) lists it.
struct PointObservation {
  size_t id = 0;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero(); ///< distorted pixel
};

class ImageStore; // ov_core/io/image_store.h

/// One image as listed in cam0/data.csv (or a ROS bag), stamped in the camera clock (t_imu = t_cam + t_d).
struct ImageEntry {
  int64_t t_cam_ns = 0;
  std::string path; ///< absolute or dataset-relative path of the image file; for a bag message, "BAG: message N"
  /// Set when the pixels live in a container (a ROS bag message) instead of a file: ovton::core::load_image() asks it.
  std::shared_ptr<const ImageStore> store;
  size_t store_index = 0; ///< which image of the store
  /// Feature-level datasets: the frame's observations instead of pixels (the image file need not exist).
  std::shared_ptr<const std::vector<PointObservation>> features;
};

/// Where `e` sits in `images`, when it is one of its entries (the replay hands out the list's own entries); nothing
/// for a copy or an entry of another list.
inline std::optional<size_t> entry_index(const std::vector<ImageEntry> &images, const ImageEntry &e) {
  const std::less<const ImageEntry *> before; // a total order, also for pointers into different objects
  if (images.empty() || before(&e, images.data()) || !before(&e, images.data() + images.size()))
    return std::nullopt;
  return static_cast<size_t>(&e - images.data());
}

/// A full navigation state sample (ground truth or estimate), stamped in the IMU clock.
/// Velocity and biases are optional: position-only sources (RTK) leave has_orientation false.
struct StateSample {
  int64_t t_ns = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity(); ///< Hamilton, body -> world
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();
  double td_s = 0.0;
  double td_sigma_s = 0.0;
  /// A rig's further cameras' own offsets and sigmas (cam1, cam2, ...) when the estimator keeps one per camera
  /// (time_offset.per_camera); empty otherwise.
  std::vector<double> cam_td_s, cam_td_sigma_s;
  /// Covariance of the pose error [δθ δp] (world-frame rotation error R = Exp(δθ)·R̂, p = p̂ + δp), for NEES;
  /// only an estimator's samples carry it.
  Eigen::Matrix<double, 6, 6> P_pose = Eigen::Matrix<double, 6, 6>::Zero();
  bool has_orientation = true;
  bool has_velocity = false;
  bool has_td = false;
  bool has_pose_cov = false;
};

/// True time offset at one image, from td_truth/data.csv: t_imu = t_cam + td.
struct TdSample {
  int64_t t_cam_ns = 0;
  double td_s = 0.0;
};

} // namespace ovton::core
