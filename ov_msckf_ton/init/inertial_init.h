#pragma once
// Initialisation without ground truth, whatever the start: static when the platform is still (gravity from the mean
// specific force, zero velocity), dynamic when it moves (dynamic_init.h). `auto` tells them apart by the images: a
// flying MAV or a walking hand-held rig can show an IMU as calm as one standing on the ground, but not still images.
#include "ov_msckf_ton/init/dynamic_init.h"
#include "ov_msckf_ton/init/init_options.h"

#include <deque>
#include <optional>
#include <string>

namespace ovton::msckf {

/// What an initialisation found: the IMU state at t_imu_ns, and for a dynamic one its covariance ([δθ δp δv δb_g
/// δb_a], state.h); a static one leaves P to the configured sigmas.
struct InitSolution {
  Eigen::Matrix3d R_WB = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero(), ba = Eigen::Vector3d::Zero();
  std::optional<Eigen::Matrix<double, 15, 15>> P;
  std::string message;
};

class InertialInitializer {
public:
  /// `opt.mode` decides what is tried: static only, dynamic only, or both (auto). sigma_px: the pixel noise of a
  /// tracked observation (update.sigma_px), for the dynamic initialisation's weights.
  InertialInitializer(const InitOptions &opt, double sigma_px, const Eigen::Matrix4d &T_BC, double focal_px,
                      double gravity_mag);

  /// Called with every image before initialisation (its IMU-clock time and the features seen in it); returns the
  /// solution once one is accepted. `why()` says what is missing until then.
  std::optional<InitSolution> try_initialize(InitFrame frame, const std::deque<ovton::core::ImuData> &imu);
  const std::string &why() const { return why_; }
  /// IMU history the initialiser needs before the newest image [s].
  double imu_window_s() const;

private:
  /// Median displacement [px] of the features seen both in the newest image and in the oldest image within `span_s`
  /// of it; nullopt when the images do not span that long yet or share fewer than 10 features.
  std::optional<double> disparity_px(double span_s) const;

  InitOptions opt_;
  bool allow_static_, allow_dynamic_;
  Eigen::Matrix4d T_BC_;
  double sigma_px_, focal_px_, gravity_mag_;
  std::deque<InitFrame> frames_;
  std::string why_ = "no image yet";
};

} // namespace ovton::msckf
