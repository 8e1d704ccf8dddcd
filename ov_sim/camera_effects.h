#pragma once
// What a real camera does to the light between the scene and the 8-bit image: it integrates over an exposure (so
// the image is blurred along the motion during it), the lens blurs (PSF) and darkens the corners (vignetting), the
// sensor adds shot and read noise, auto-exposure changes exposure time and gain from frame to frame, mains lamps may
// flicker, and the result is rounded to 8 bits. Off (the clean renderer) unless `enabled`.
//
// Time convention: the image stamp (its IMU-clock instant t_k, and td_truth) is the MIDDLE of the exposure: the
// exposure runs over [t_k - T/2, t_k + T/2] (per row when the shutter rolls: row v over its own instant +- T/2).
#include "ov_core/cam/camera_model.h"
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

namespace ovton::sim {

struct CameraEffectsOptions {
  bool enabled = false;
  double exposure_s = 0.004; ///< fixed exposure, or the first frame's under auto-exposure
  bool auto_exposure = true;
  double ae_target = 140.0;          ///< mean grey level auto-exposure aims for
  double ae_min_exposure_s = 0.0001; ///< exposure range of auto-exposure
  double ae_max_exposure_s = 0.010;
  double ae_max_gain = 4.0; ///< analogue gain used once the exposure is at its maximum
  double ae_rate = 0.5;     ///< share of the log-brightness error corrected per frame (damped, lags)
  /// Scene brightness: the exposure at which a radiance grey level g gives g at gain 1 (without vignetting).
  double scene_exposure_s = 0.003;
  double blur_step_px = 1.0;      ///< sub-frame poses this close in image motion (px) while the shutter is open
  int blur_max_samples = 24;      ///< at most this many sub-frame renderings per image
  double vignetting = 0.3;        ///< relative brightness loss at the image corners (cos^4-like falloff)
  double psf_sigma_px = 0.6;      ///< Gaussian optics blur [px]; 0 = none
  double full_well_e = 6000.0;    ///< electrons at full scale (255) at gain 1: sets the shot noise
  double read_noise_e = 8.0;      ///< read noise [electrons]
  double flicker_amplitude = 0.0; ///< relative modulation of the lamps (0 = steady light)
  double flicker_hz = 100.0;      ///< twice the mains frequency
};

/// Throws UsageError naming the first option out of range.
void check(const CameraEffectsOptions &o);

/// The exposure a frame is taken with.
struct Exposure {
  double exposure_s = 0.0;
  double gain = 1.0;
};

/// Develops exposure-averaged radiance into 8-bit images, frame after frame, and runs auto-exposure. Deterministic:
/// the noise of frame k depends only on (seed, k), the exposure only on the frames before.
class CameraEffects {
public:
  CameraEffects(const CameraEffectsOptions &opt, const ovton::core::CameraModel &cam, uint64_t noise_seed);

  /// Exposure of the next frame (auto-exposure decides it from the frames already developed, as a camera does).
  const Exposure &next_exposure() const { return next_; }

  /// radiance: CV_32F of the camera's size, the scene's grey level averaged over the exposure (Renderer::accumulate).
  /// t_mid_ns: IMU-clock middle of the exposure (flicker phase). Writes `out` (CV_8U) and updates the exposure.
  /// row_dt_s: the rolling-shutter readout (row v is exposed v/height * readout later), for the flicker phase.
  void develop(const cv::Mat &radiance, int64_t t_mid_ns, double readout_s, uint64_t frame_index, cv::Mat &out);

  /// Auto-exposure settled on a first view before recording starts (a camera that has been running): sets the next
  /// exposure so that this radiance develops to the target mean. No effect with a fixed exposure.
  void settle(const cv::Mat &radiance);

  /// Sub-frame renderings needed for an image moving `motion_px` during its exposure.
  int blur_samples(double motion_px) const;

  const CameraEffectsOptions &options() const { return opt_; }

private:
  double flicker_factor(int64_t t_mid_ns, double exposure_s) const;
  /// Mean grey level (noise-free, saturated) that `irradiance` develops to with exposure x gain = product.
  double developed_mean(const cv::Mat &irradiance, double product) const;
  void set_exposure_product(double product);
  CameraEffectsOptions opt_;
  uint64_t noise_seed_;
  cv::Mat vignette_; ///< CV_32F per-pixel gain
  Exposure next_;
};

} // namespace ovton::sim
