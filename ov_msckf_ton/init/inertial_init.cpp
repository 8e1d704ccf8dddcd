#include "ov_msckf_ton/init/inertial_init.h"
#include "ov_msckf_ton/core/static_init.h"

#include <algorithm>
#include <unordered_map>

namespace ovton::msckf {

InertialInitializer::InertialInitializer(const InitOptions &opt, double sigma_px, const Eigen::Matrix4d &T_BC,
                                         double focal_px, double gravity_mag)
    : opt_(opt), allow_static_(opt.mode != InitMode::Dynamic),
      allow_dynamic_(opt.mode == InitMode::Auto || opt.mode == InitMode::Dynamic), T_BC_(T_BC), sigma_px_(sigma_px),
      focal_px_(focal_px), gravity_mag_(gravity_mag) {}

double InertialInitializer::imu_window_s() const {
  return std::max(opt_.window_s, opt_.dynamic.window_s);
}

std::optional<double> InertialInitializer::disparity_px(double span_s) const {
  const InitFrame &newest = frames_.back();
  const int64_t span_ns = ovton::core::s_to_ns(span_s);
  if (newest.t_cam_ns - frames_.front().t_cam_ns < span_ns)
    return std::nullopt;
  // The oldest image still within the span.
  auto old = std::find_if(frames_.begin(), frames_.end(),
                          [&](const InitFrame &f) { return newest.t_cam_ns - f.t_cam_ns <= span_ns; });
  std::unordered_map<size_t, Eigen::Vector2d> then;
  for (const auto &[id, xy] : old->obs)
    then.emplace(id, xy);
  std::vector<double> d;
  for (const auto &[id, xy] : newest.obs)
    if (auto it = then.find(id); it != then.end())
      d.push_back(focal_px_ * (xy - it->second).norm());
  if (d.size() < 10)
    return std::nullopt;
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

std::optional<InitSolution> InertialInitializer::try_initialize(InitFrame frame,
                                                                const std::deque<ovton::core::ImuData> &imu) {
  frames_.push_back(std::move(frame));
  const double keep_s = std::max(opt_.dynamic.window_s, opt_.still_window_s);
  while (frames_.size() > 2 && frames_.back().t_cam_ns - frames_[1].t_cam_ns >= ovton::core::s_to_ns(keep_s))
    frames_.pop_front();
  const int64_t t_imu = frames_.back().t_imu_ns;

  // Still: the images say so (a calm IMU alone is no proof), then the IMU gives gravity and the gyro bias.
  const std::optional<double> still_px = disparity_px(opt_.still_window_s);
  const bool images_still = still_px && *still_px < opt_.still_max_disparity_px;
  if (allow_static_ && (images_still || !allow_dynamic_)) {
    const StaticInitResult r = static_initialize(imu, t_imu, opt_.window_s, opt_.max_accel_std, opt_.max_gyro_std);
    if (r.ok) {
      InitSolution s;
      s.R_WB = r.R_WB;
      s.bg = r.bg;
      s.ba = r.ba;
      s.message = "static initialisation (accel std " + std::to_string(r.accel_std) + " m/s^2" +
                  (still_px ? ", image disparity " + std::to_string(*still_px) + " px" : std::string()) + ")";
      return s;
    }
    why_ = r.why;
    return std::nullopt;
  }
  if (!allow_dynamic_) {
    why_ = "images are not still yet";
    return std::nullopt;
  }
  if (!still_px && allow_static_) {
    why_ = "waiting for " + std::to_string(opt_.still_window_s) + " s of images to tell still from moving";
    return std::nullopt;
  }
  // Moving: the dynamic initialiser over the frames of its window.
  std::vector<InitFrame> window;
  for (const auto &f : frames_)
    if (frames_.back().t_cam_ns - f.t_cam_ns <= ovton::core::s_to_ns(opt_.dynamic.window_s))
      window.push_back(f);
  if (window.back().t_cam_ns - window.front().t_cam_ns < ovton::core::s_to_ns(0.9 * opt_.dynamic.window_s)) {
    why_ = "moving: collecting " + std::to_string(opt_.dynamic.window_s) + " s of images for a dynamic initialisation";
    return std::nullopt;
  }
  const DynamicInitResult r = dynamic_initialize(window, imu, T_BC_, focal_px_, gravity_mag_, opt_.sigma_yaw,
                                                 opt_.sigma_pos, sigma_px_, opt_.dynamic);
  if (!r.ok) {
    why_ = "dynamic initialisation: " + r.why;
    return std::nullopt;
  }
  InitSolution s;
  s.R_WB = r.R_WB;
  s.p = r.p_W;
  s.v = r.v_W;
  s.bg = r.bg;
  s.ba = r.ba;
  s.P = r.P;
  s.message = "dynamic initialisation: " + r.why;
  return s;
}

} // namespace ovton::msckf
