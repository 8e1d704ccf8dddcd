#pragma once
// Scores a front end's feature tracks against the ground truth: each track's point is fitted to its observations
// with the ground-truth camera poses (at t_cam + t_d,true) held fixed, and every observation's pixel error is the
// difference between where the tracker put it and where that point projects. On rendered folders the poses are
// exact, so the errors are the tracker's alone: how large (against the filter's sigma_px), how biased, how
// correlated along a track (KLT drift), how many outliers, and how long the tracks live.
#include "ov_core/io/dataset.h"

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace ovton::eval {

/// One tracked observation, as in cam0/features.csv (distorted pixels, camera clock).
struct TrackPoint {
  int64_t t_cam_ns = 0;
  uint64_t id = 0;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
};

struct TrackTruthOptions {
  int min_obs = 3;          ///< tracks shorter than this are counted but not scored (3 dof need > 3 rows)
  double min_depth_m = 0.1; ///< a fitted point closer than this to any observing camera is not scored
  double huber_px = 2.0;    ///< the point fit down-weights larger errors, so one slip does not move it
  int max_segment = 20;     ///< tracks are scored in pieces of at most this many observations (the window)
};

struct TrackTruthResult {
  long tracks = 0, observations = 0;                ///< everything read
  long tracks_short = 0;                            ///< fewer than min_obs observations (not scored)
  long tracks_failed = 0;                           ///< no point could be fitted (parallel rays, behind a camera)
  long segments = 0, obs_scored = 0;                ///< scored pieces (a long track is cut into window-sized segments)
  double len_mean = 0, len_median = 0, len_p90 = 0; ///< track length [frames] over all tracks
  double len_mean_ge2 = 0;                          ///< over tracks seen in at least two frames
  /// Pixel error [px] with the dof the point fit took out (2n − 3 per segment): the sigma the filter should use.
  double sigma_px = 0;
  /// Same, leaving out observations with error above 3 px (what sigma would be without outliers).
  double sigma_inlier_px = 0;
  double mad_sigma_px = 0;                                       ///< 1.4826 × median |error| per axis (robust), pooled
  double mean_u = 0, mean_v = 0;                                 ///< bias [px]
  double rms_u = 0, rms_v = 0;                                   ///< per axis, without the dof correction
  double frac_gt1 = 0, frac_gt2 = 0, frac_gt3 = 0, frac_gt5 = 0; ///< share of observations with |error| above
  double lag1_corr = 0; ///< correlation of consecutive errors along a segment (0: white, → 1: drift)
  /// Error against the point's true image velocity: e ≈ k·v fitted over all observations, k in ms. A shift along
  /// the motion (motion blur, an exposure that is not centred on the stamp) reads as a time offset.
  double vel_slope_ms = 0;
  /// Chi-square per dof of each segment at the given sigma (what the MSCKF gate sees): mean and share above the
  /// 95 % quantile, for sigma 0.5 and 1 px.
  double chi2_dof_mean_05 = 0, chi2_dof_mean_1 = 0, gated_05 = 0, gated_1 = 0;
  /// RMS error by observation age within its track: ages 0-4, 5-9, 10-19, 20+ frames.
  double rms_age[4] = {0, 0, 0, 0};
  long n_age[4] = {0, 0, 0, 0};
};

/// Reads cam0/features.csv rows (timestamp_ns,feature_id,u,v); throws DataError naming file and line.
std::vector<TrackPoint> read_track_points(const std::string &csv);

/// Throws ovton::core::UsageError when the dataset has no full-pose ground truth.
TrackTruthResult score_tracks(const std::vector<TrackPoint> &points, const ovton::core::Dataset &data,
                              const TrackTruthOptions &opt = {});

/// How rewrite_tracks replaces the observations.
enum class TrackRewrite {
  Truth,   ///< the exact projection of the track's point (no error at all)
  White,   ///< the projection plus white Gaussian noise, sigma_px per axis
  Ar1,     ///< plus Gaussian noise correlated along the track, e_k = rho e_{k-1} + sqrt(1 - rho^2) sigma n_k
  Shuffle, ///< plus the tracker's own errors (from window-sized segments), permuted across all tracks: the same
           ///< sizes and outliers, no correlation along a track
};

/// Experiments on what in the tracker's errors matters to the filter: every track whose point can be fitted (one
/// point per whole track, ground-truth poses) is rewritten as that point's projections plus the chosen error; tracks
/// that cannot be fitted are dropped. Same ids and stamps, so `ovton run` on the result sees the same track lengths.
std::vector<TrackPoint> rewrite_tracks(const std::vector<TrackPoint> &points, const ovton::core::Dataset &data,
                                       TrackRewrite how, double sigma_px, double rho, uint64_t seed,
                                       const TrackTruthOptions &opt = {});

/// Markdown table (one row per statistic) with a short legend.
std::string track_truth_table(const TrackTruthResult &r);

} // namespace ovton::eval
