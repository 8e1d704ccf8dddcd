// What the calibration fit takes from a recording (camera_imu_calib.h): the image pairs' tracks and the IMU's noise.
#include "ov_core/cam/camera_model.h"
#include "ov_core/io/image_store.h"
#include "ov_core/track/track_klt.h"
#include "ov_core/types/errors.h"
#include "ov_core/types/time.h"
#include "ov_msckf_ton/calib/camera_imu_calib.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <unordered_map>

namespace ovton::msckf {

std::vector<CalibPair> track_calib_pairs(const std::vector<ovton::core::ImageEntry> &images, size_t first, size_t last,
                                         int width, int height, double f_px, const CalibImageLoader &load) {
  ovton::core::CameraCalib guess;
  guess.width = width;
  guess.height = height;
  guess.intrinsics << f_px, f_px, 0.5 * width, 0.5 * height;
  const ovton::core::CameraModel camera(guess);
  ovton::core::TrackKLTOptions topt;
  // The tracker's RANSAC runs on the guessed focal: 2 px there stays loose enough for a focal 20 % off.
  topt.ransac_px = 2.0;
  topt.num_features = 150;
  ovton::core::TrackKLT tracker(camera, topt);
  std::vector<CalibPair> pairs;
  std::unordered_map<size_t, Eigen::Vector2d> prev;
  int64_t t_prev = 0;
  for (size_t i = first; i < std::min(last, images.size()); ++i) {
    const auto &feats = tracker.track(images[i].t_cam_ns, load(images[i]));
    std::unordered_map<size_t, Eigen::Vector2d> curr;
    for (const auto &f : feats)
      curr[f.id] = f.uv;
    if (i > first) {
      CalibPair q;
      q.t0_cam_ns = t_prev;
      q.t1_cam_ns = images[i].t_cam_ns;
      for (const auto &f : feats)
        if (auto it = prev.find(f.id); it != prev.end()) {
          q.uv0.push_back(it->second);
          q.uv1.push_back(f.uv);
        }
      pairs.push_back(std::move(q));
    }
    prev = std::move(curr);
    t_prev = images[i].t_cam_ns;
  }
  return pairs;
}

CalibResult calibrate_recording(const ovton::core::Dataset &d, double from_s, double to_s, const CalibOptions &opt) {
  const auto load = [](const ovton::core::ImageEntry &e) {
    cv::Mat img = ovton::core::load_image(e);
    if (img.empty())
      throw ovton::core::DataError(e.path, "unreadable image (listed for stamp " + std::to_string(e.t_cam_ns) + ")");
    return img;
  };
  if (d.images.empty())
    throw ovton::core::DataError(d.root, "no images");
  const cv::Mat first = load(d.images.front());
  const int64_t t0 = d.images.front().t_cam_ns;
  size_t b = 0, e = d.images.size();
  while (b < e && ovton::core::ns_to_s(d.images[b].t_cam_ns - t0) < from_s)
    ++b;
  if (to_s > 0)
    while (e > b && ovton::core::ns_to_s(d.images[e - 1].t_cam_ns - t0) >= to_s)
      --e;
  const double f0 = 0.5 * first.cols / std::tan(0.5 * opt.hfov_prior_deg * M_PI / 180.0);
  const std::vector<CalibPair> pairs = track_calib_pairs(d.images, b, e, first.cols, first.rows, f0, load);
  return calibrate_camera_imu(pairs, d.imu, first.cols, first.rows, opt, d.root);
}

namespace {

/// Floors for a phone-grade IMU whose figures nobody gave: several times a MEMS datasheet's, because arrival-time
/// stamps (jitter of milliseconds on rates of rad/s) and vibration add error a datasheet does not know.
constexpr double kGyroNoiseFloor = 2.0e-3;  // rad/s/sqrt(Hz)
constexpr double kAccelNoiseFloor = 2.0e-2; // m/s^2/sqrt(Hz)
constexpr double kGyroWalk = 1.0e-4;        // rad/s^2/sqrt(Hz)
constexpr double kAccelWalk = 2.0e-3;       // m/s^3/sqrt(Hz)
/// A window counts as still below these per-axis standard deviations.
constexpr double kStillGyroStd = 0.03, kStillAccelStd = 0.15;

double axis_std_max(const std::vector<ovton::core::ImuData> &imu, size_t b, size_t e, bool gyro) {
  Eigen::Vector3d s = Eigen::Vector3d::Zero(), s2 = Eigen::Vector3d::Zero();
  for (size_t i = b; i < e; ++i) {
    const Eigen::Vector3d &v = gyro ? imu[i].wm : imu[i].am;
    s += v;
    s2 += v.cwiseProduct(v);
  }
  const double n = static_cast<double>(e - b);
  return ((s2 / n - (s / n).cwiseProduct(s / n)).cwiseMax(0.0)).cwiseSqrt().maxCoeff();
}

} // namespace

ImuNoiseEstimate estimate_imu_noise(const std::vector<ovton::core::ImuData> &imu) {
  ImuNoiseEstimate est;
  std::vector<int64_t> dt;
  for (size_t i = 1; i < imu.size(); ++i)
    dt.push_back(imu[i].t_imu_ns - imu[i - 1].t_imu_ns);
  if (!dt.empty()) {
    std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
    est.rate_hz = 1.0 / ovton::core::ns_to_s(std::max<int64_t>(dt[dt.size() / 2], 1));
  }
  est.calib.rate_hz = est.rate_hz > 0 ? est.rate_hz : 200.0;
  est.calib.gyro_noise_density = kGyroNoiseFloor;
  est.calib.accel_noise_density = kAccelNoiseFloor;
  est.calib.gyro_random_walk = kGyroWalk;
  est.calib.accel_random_walk = kAccelWalk;
  const auto win = static_cast<size_t>(std::max(10.0, est.rate_hz * est.window_s));
  double best = 1e300;
  size_t best_b = 0;
  for (size_t b = 0; b + win <= imu.size(); b += std::max<size_t>(1, win / 10)) {
    const double g = axis_std_max(imu, b, b + win, true);
    if (g < best) {
      best = g;
      best_b = b;
    }
  }
  if (best >= 1e300)
    return est;
  est.gyro_std = best;
  est.accel_std = axis_std_max(imu, best_b, best_b + win, false);
  est.still_begin_s = ovton::core::ns_to_s(imu[best_b].t_imu_ns - imu.front().t_imu_ns);
  est.still_found = est.gyro_std < kStillGyroStd && est.accel_std < kStillAccelStd;
  if (est.still_found) {
    // Discrete white noise of std σ at rate r is a density of σ/√r.
    est.calib.gyro_noise_density = std::max(kGyroNoiseFloor, est.gyro_std / std::sqrt(est.rate_hz));
    est.calib.accel_noise_density = std::max(kAccelNoiseFloor, est.accel_std / std::sqrt(est.rate_hz));
  }
  return est;
}

std::string ImuNoiseEstimate::summary() const {
  char s[600];
  const double gd = rate_hz > 0 ? gyro_std / std::sqrt(rate_hz) : 0,
               ad = rate_hz > 0 ? accel_std / std::sqrt(rate_hz) : 0;
  std::snprintf(s, sizeof s,
                "IMU noise (no figures given): median rate %.1f Hz; stillest %.1f s at %.1f s: gyro std %.4f rad/s, "
                "accel std %.4f m/s^2 (%s: densities %.2e rad/s/sqrt(Hz), %.2e m/s^2/sqrt(Hz))\n"
                "  written: gyro %.2e rad/s/sqrt(Hz), accel %.2e m/s^2/sqrt(Hz) (measured where above the phone "
                "floors %.0e, %.0e); random walks %.0e rad/s^2/sqrt(Hz), %.0e m/s^3/sqrt(Hz): defaults, not "
                "observable from the log",
                rate_hz, window_s, still_begin_s, gyro_std, accel_std, still_found ? "still" : "not still: not used",
                gd, ad, calib.gyro_noise_density, calib.accel_noise_density, kGyroNoiseFloor, kAccelNoiseFloor,
                calib.gyro_random_walk, calib.accel_random_walk);
  return s;
}

std::string CalibResult::summary() const {
  const Eigen::Vector3d rpy = ovton::core::so3_log(R_IC) * 180.0 / M_PI;
  const Eigen::Vector3d rpy0 = ovton::core::so3_log(coarse_R_IC) * 180.0 / M_PI;
  char s[2000];
  std::snprintf(
      s, sizeof s,
      "pairs %d of %d (%ld features), %d iterations, %.1f s; residual RMS %.2f px (within 3 Huber), %.0f %% inliers\n"
      "t_d        %8.2f ± %.2f ms   (t_imu = t_cam + t_d, middle row; coarse grid %.1f ms)\n"
      "focal      %8.1f ± %.1f px   (prior %.1f px; principal point fixed at the centre %.1f, %.1f)\n"
      "readout    %8.2f ± %.2f ms%s\n"
      "R_IC       rotation vector (%.2f, %.2f, %.2f) deg, σ (%.2f, %.2f, %.2f) deg\n"
      "           [% .4f % .4f % .4f; % .4f % .4f % .4f; % .4f % .4f % .4f]\n"
      "corr(t_d, .) rot %.2f %.2f %.2f, f %.2f, t_r %.2f\n"
      "coarse R_IC rotation vector (%.2f, %.2f, %.2f) deg; robust cost %.1f px^2\n"
      "gyro bias  (%.4f, %.4f, %.4f) ± (%.4f, %.4f, %.4f) rad/s\n"
      "σ sources  sandwich: rot %.2f deg, f %.1f px, t_d %.2f ms, t_r %.2f ms; jackknife (%zu blocks): rot %.2f deg, "
      "f %.1f px, t_d %.2f ms, t_r %.2f ms (each σ above is the larger)",
      pairs_used, pairs_total, features_used, iterations, seconds, rms_px, 100 * inlier_share, td_s * 1e3,
      sigma_td_s * 1e3, coarse_td_s * 1e3, focal_px, sigma_focal_px, focal_prior_px, cu, cv, readout_s * 1e3,
      sigma_readout_s * 1e3, readout_estimated ? "" : " (not estimated)", rpy.x(), rpy.y(), rpy.z(),
      sigma_rot_rad.x() * 180 / M_PI, sigma_rot_rad.y() * 180 / M_PI, sigma_rot_rad.z() * 180 / M_PI, R_IC(0, 0),
      R_IC(0, 1), R_IC(0, 2), R_IC(1, 0), R_IC(1, 1), R_IC(1, 2), R_IC(2, 0), R_IC(2, 1), R_IC(2, 2), correlation(4, 0),
      correlation(4, 1), correlation(4, 2), correlation(4, 3), correlation(4, 5), rpy0.x(), rpy0.y(), rpy0.z(),
      robust_cost, gyro_bias.x(), gyro_bias.y(), gyro_bias.z(), sigma_gyro_bias.x(), sigma_gyro_bias.y(),
      sigma_gyro_bias.z(), sigma_sandwich(0) * 180 / M_PI, sigma_sandwich(1), sigma_sandwich(2) * 1e3,
      sigma_sandwich(3) * 1e3, jackknife_td_s.size(), sigma_jackknife(0) * 180 / M_PI, sigma_jackknife(1),
      sigma_jackknife(2) * 1e3, sigma_jackknife(3) * 1e3);
  return s;
}

} // namespace ovton::msckf
