#pragma once
// The coarse t_d search's arithmetic (td_search.h drives it): a rotation-only fit of two images' bearings, the
// gyro's angular acceleration over a window, and the fit of t_d to the images' rotation rates.
#include "ov_core/types/imu_buffer.h"
#include "ov_msckf_ton/init/init_options.h"

#include <Eigen/Core>
#include <vector>

namespace ovton::msckf {

struct TdSearchResult; // td_search.h

/// One pair of consecutive images: the body rate the images saw between them.
struct PairRate {
  double t0, t1;     ///< camera-clock seconds after the first image
  Eigen::Vector3d w; ///< body frame [rad/s]
};

/// Rotation R with a_i ≈ R·c_i for unit bearings (Kabsch with Huber weights, threshold `huber` in radians).
Eigen::Matrix3d fit_rotation(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &c,
                             double huber);

/// RMS angular acceleration of images [b, e) (seconds after the first image) from the gyro's mean rate per image
/// interval at t_d = prior.
double rms_alpha(const std::vector<double> &t_img, size_t b, size_t e, const ovton::core::GyroIntegral &gyro,
                 double prior);

/// Fits t_d ∈ prior ± opt.range_s to the pairs' rates (camera seconds after t0_ns) against the gyro of `imu`: fills
/// res.td_s, sigma_s, residual_sigma, cost_profile and pairs, and res.found when the best candidate is trustworthy
/// (otherwise res.why says why not). Pairs the gyro does not cover over the whole range are left out first.
void fit_offset(std::vector<PairRate> pairs, const ovton::core::ImuBuffer &imu, int64_t t0_ns, double prior_td_s,
                const TdSearchOptions &opt, TdSearchResult &res);

} // namespace ovton::msckf
