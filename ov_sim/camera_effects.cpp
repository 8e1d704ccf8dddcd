#include "ov_sim/camera_effects.h"
#include "ov_core/types/errors.h"
#include "ov_sim/hash_noise.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace ovton::sim {

void check(const CameraEffectsOptions &o) {
  const auto need = [](bool ok, const char *what) {
    if (!ok)
      throw ovton::core::UsageError(std::string("camera effects: ") + what);
  };
  need(o.exposure_s > 0 && o.exposure_s <= 0.05, "exposure must lie in (0, 50 ms]");
  need(o.ae_min_exposure_s > 0 && o.ae_max_exposure_s >= o.ae_min_exposure_s && o.ae_max_exposure_s <= 0.05,
       "auto-exposure range must satisfy 0 < min <= max <= 50 ms");
  need(o.ae_target > 0 && o.ae_target < 255, "auto-exposure target must lie in (0, 255)");
  need(o.ae_max_gain >= 1, "maximum gain must be >= 1");
  need(o.ae_rate > 0 && o.ae_rate <= 1, "auto-exposure rate must lie in (0, 1]");
  need(o.scene_exposure_s > 0, "scene exposure must be positive");
  need(o.blur_step_px > 0 && o.blur_max_samples >= 1, "blur step must be positive and samples >= 1");
  need(o.vignetting >= 0 && o.vignetting < 1, "vignetting must lie in [0, 1)");
  need(o.psf_sigma_px >= 0 && o.psf_sigma_px <= 5, "PSF sigma must lie in [0, 5] px");
  need(o.full_well_e > 0 && o.read_noise_e >= 0, "full well must be positive, read noise >= 0");
  need(o.flicker_amplitude >= 0 && o.flicker_amplitude < 1 && o.flicker_hz > 0,
       "flicker amplitude must lie in [0, 1), frequency > 0");
}

CameraEffects::CameraEffects(const CameraEffectsOptions &opt, const ovton::core::CameraModel &cam, uint64_t noise_seed)
    : opt_(opt), noise_seed_(noise_seed) {
  check(opt_);
  const int w = cam.width(), h = cam.height();
  // cos^4 falloff around the principal point, scaled so that the farthest corner loses `vignetting`:
  // V(r) = 1 / (1 + (r/f)^2)^2 with f from V(r_max) = 1 - vignetting.
  const double cu = cam.calib().intrinsics(2), cv_ = cam.calib().intrinsics(3);
  const double r_max = std::hypot(std::max(cu, w - 1 - cu), std::max(cv_, h - 1 - cv_));
  const double t2 = 1.0 / std::sqrt(1.0 - opt_.vignetting) - 1.0; // (r_max / f)^2
  const double inv_f2 = t2 / (r_max * r_max);
  vignette_.create(h, w, CV_32F);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const double q = 1.0 + ((u - cu) * (u - cu) + (v - cv_) * (v - cv_)) * inv_f2;
      vignette_.at<float>(v, u) = static_cast<float>(1.0 / (q * q));
    }
  next_.exposure_s = std::clamp(opt_.exposure_s, opt_.auto_exposure ? opt_.ae_min_exposure_s : 0.0,
                                opt_.auto_exposure ? opt_.ae_max_exposure_s : 1.0);
  next_.gain = 1.0;
}

int CameraEffects::blur_samples(double motion_px) const {
  if (!(motion_px > 0))
    return 1;
  return std::clamp(static_cast<int>(std::ceil(motion_px / opt_.blur_step_px)), 1, opt_.blur_max_samples);
}

double CameraEffects::flicker_factor(int64_t t_ns, double exposure_s) const {
  if (opt_.flicker_amplitude <= 0)
    return 1.0;
  // Mean of 1 + a sin(w t) over the exposure: exact for light that is steady apart from the lamps' modulation.
  // The phase uses t modulo one second, exact for whole-hertz frequencies and free of the 1e9 s epoch's rounding.
  const double w = 2.0 * M_PI * opt_.flicker_hz;
  const double t = static_cast<double>(t_ns % 1000000000LL) * 1e-9;
  const double t0 = t - exposure_s / 2, t1 = t + exposure_s / 2;
  return 1.0 + opt_.flicker_amplitude * (std::cos(w * t0) - std::cos(w * t1)) / (w * exposure_s);
}

void CameraEffects::develop(const cv::Mat &radiance, int64_t t_mid_ns, double readout_s, uint64_t frame_index,
                            cv::Mat &out) {
  if (radiance.size() != vignette_.size() || radiance.type() != CV_32F)
    throw ovton::core::UsageError("camera effects: radiance must be CV_32F of the camera's size");
  cv::Mat irr;
  if (opt_.psf_sigma_px > 0)
    cv::GaussianBlur(radiance, irr, cv::Size(0, 0), opt_.psf_sigma_px, opt_.psf_sigma_px, cv::BORDER_REFLECT);
  else
    irr = radiance;
  const Exposure ex = next_;
  const double scale = ex.exposure_s / opt_.scene_exposure_s * ex.gain;
  const float e_per_dn = static_cast<float>(opt_.full_well_e / 255.0 / ex.gain); // electrons per output grey level
  const float dn_per_e = 1.0f / e_per_dn, read2 = static_cast<float>(opt_.read_noise_e * opt_.read_noise_e);
  const uint64_t seed = noise_key(noise_seed_, frame_index);
  const int w = irr.cols, h = irr.rows;
  out.create(h, w, CV_8U);
  double sum = 0.0;
  for (int v = 0; v < h; ++v) {
    const int64_t t_row = t_mid_ns + static_cast<int64_t>(std::llround(readout_s * 1e9 * v / h));
    const float s = static_cast<float>(scale * flicker_factor(t_row, ex.exposure_s));
    const float *r = irr.ptr<float>(v), *vig = vignette_.ptr<float>(v);
    uint8_t *o = out.ptr<uint8_t>(v);
    for (int u = 0; u < w; ++u) {
      const float mean = std::max(0.0f, r[u] * vig[u] * s);
      sum += std::min(mean, 255.0f);
      // Shot noise (Poisson in electrons, Gaussian at these counts) and read noise, converted to grey levels.
      const float sigma = std::sqrt(mean * e_per_dn + read2) * dn_per_e;
      const float val = mean + sigma * approx_normal(noise_key(seed, static_cast<uint64_t>(v) * w + u));
      o[u] = static_cast<uint8_t>(std::clamp(val + 0.5f, 0.0f, 255.0f));
    }
  }
  if (!opt_.auto_exposure)
    return;
  // Auto-exposure: move exposure x gain a damped step towards the target mean. A dark frame brightens the next one.
  const double mean = std::max(1.0, sum / (static_cast<double>(w) * h));
  set_exposure_product(ex.exposure_s * ex.gain * std::pow(opt_.ae_target / mean, opt_.ae_rate));
}

void CameraEffects::set_exposure_product(double product) {
  // Exposure first, gain once the exposure is at its maximum (as sensors do, to keep noise low).
  next_.exposure_s = std::clamp(product, opt_.ae_min_exposure_s, opt_.ae_max_exposure_s);
  next_.gain = std::clamp(product / next_.exposure_s, 1.0, opt_.ae_max_gain);
}

double CameraEffects::developed_mean(const cv::Mat &irradiance, double product) const {
  const float s = static_cast<float>(product / opt_.scene_exposure_s);
  double sum = 0.0;
  for (int v = 0; v < irradiance.rows; ++v) {
    const float *r = irradiance.ptr<float>(v), *vig = vignette_.ptr<float>(v);
    for (int u = 0; u < irradiance.cols; ++u)
      sum += std::clamp(r[u] * vig[u] * s, 0.0f, 255.0f);
  }
  return sum / static_cast<double>(irradiance.total());
}

void CameraEffects::settle(const cv::Mat &radiance) {
  if (!opt_.auto_exposure)
    return;
  if (radiance.size() != vignette_.size() || radiance.type() != CV_32F)
    throw ovton::core::UsageError("camera effects: radiance must be CV_32F of the camera's size");
  // Undamped steps of the same law converge in a few iterations (saturation makes it slightly non-linear).
  double product = next_.exposure_s * next_.gain;
  for (int i = 0; i < 8; ++i)
    product *= opt_.ae_target / std::max(1.0, developed_mean(radiance, product));
  set_exposure_product(product);
}

} // namespace ovton::sim
