#pragma once
// Track statistics of an image sequence, real or rendered: how long a standard KLT front end keeps features, how
// many it must replace, how well its tracks survive a forward-backward check, and what the images' gradients and
// noise look like. The yardstick for "are rendered images as hard as real ones" (issue 13, docs/simulate.md).
//
// The tracker is deliberately a plain OpenCV check, not the filter's front end: it has no RANSAC, no histogram
// equalisation and no grid, so that the numbers describe the images rather than the project's tuning.
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace ovton::eval {

struct TrackStatsOptions {
  int max_points = 200;           ///< points kept alive; new ones are detected to refill
  int win_size = 21;              ///< LK window side [px]
  int pyr_levels = 3;             ///< pyramid images (OpenCV maxLevel = pyr_levels - 1)
  double fb_max_px = 0.5;         ///< forward-backward round-trip error above which a track ends [px]
  double mask_radius_px = 15;     ///< no new detection this close to a live point [px]
  double gftt_quality = 0.01;     ///< Shi-Tomasi quality level (relative to the frame's best corner)
  int gftt_block = 7;             ///< Shi-Tomasi block size
  double low_gradient = 20.0;     ///< Sobel (3x3) gradient magnitude below which a pixel counts as plain
  int64_t t_begin_ns = INT64_MIN; ///< only images stamped in [t_begin_ns, t_end_ns] (camera clock)
  int64_t t_end_ns = INT64_MAX;
};

/// Per-frame numbers, in image order.
struct FrameTrackStats {
  int64_t t_cam_ns = 0;
  int tracked = 0;                 ///< points carried over from the previous frame (after the forward-backward check)
  int detected = 0;                ///< new points detected in this frame
  double new_share = 0.0;          ///< detected / (tracked + detected); the first frame counts as all new
  double fb_median_px = 0.0;       ///< median forward-backward error of the points LK found in this frame
  double low_gradient_share = 0.0; ///< share of pixels whose Sobel magnitude is below options.low_gradient
  double gradient_median = 0.0;    ///< median Sobel magnitude
  double noise_sigma = 0.0;        ///< grey-level noise estimate (Immerkaer's Laplacian-difference estimator)
  double mean_intensity = 0.0;
};

/// Image-level numbers of one frame (also used alone, e.g. in tests of the renderer).
struct GradientStats {
  double low_share = 0.0, median = 0.0, p90 = 0.0, noise_sigma = 0.0, mean_intensity = 0.0;
};
GradientStats gradient_stats(const cv::Mat &gray8, double low_gradient = 20.0);

/// Immerkaer (1996) fast noise variance estimate: the image convolved with the difference of two Laplacians, whose
/// response to locally planar intensity is zero, averaged in absolute value. Edges bias it upwards slightly; for
/// the comparisons here (same scene type, real vs rendered) that bias is common to both.
double noise_sigma_estimate(const cv::Mat &gray8);

struct TrackStatsSummary {
  size_t frames = 0;
  double tracked_median = 0.0;
  double new_share_mean = 0.0;   ///< over frames after the first
  double new_share_median = 0.0; ///< over frames after the first
  /// Track length = frames a feature is seen in. Tracks are features seen in >= 2 frames (what a filter can use);
  /// detections lost at their first tracking attempt are counted apart. Tracks still alive in the last frame are
  /// included with their length so far (so the sequence length caps them; `censored` says how many).
  double track_length_median = 0.0, track_length_p25 = 0.0, track_length_p75 = 0.0, track_length_mean = 0.0;
  size_t tracks = 0, lost_at_once = 0, censored = 0;
  double fb_median_px = 0.0, fb_p90_px = 0.0; ///< over all points LK found (before the threshold)
  double fb_reject_share = 0.0;               ///< share of LK-found points rejected by the forward-backward check
  double low_gradient_share = 0.0;            ///< mean over frames
  double gradient_median = 0.0, noise_sigma = 0.0, mean_intensity = 0.0; ///< medians over frames
};

struct TrackStatsResult {
  std::vector<FrameTrackStats> frames;
  std::vector<int> track_lengths; ///< every track (>= 2 frames), in the order they ended
  std::vector<double> fb_errors;  ///< every forward-backward error measured [px]
  TrackStatsSummary summary;
};

/// Runs the check over images in order. `images` are (stamp, file) pairs; files are read as 8-bit grey.
/// Throws DataError naming an unreadable file, UsageError for bad options or fewer than 2 images in the span.
TrackStatsResult track_statistics(const std::vector<std::pair<int64_t, std::string>> &images,
                                  const TrackStatsOptions &opt = {});

/// Same on images already in memory (tests).
TrackStatsResult track_statistics(const std::vector<std::pair<int64_t, cv::Mat>> &images,
                                  const TrackStatsOptions &opt = {});

/// Summary as "key: value" lines (YAML), and per-frame numbers as CSV with a header.
std::string summary_yaml(const TrackStatsSummary &s, const TrackStatsOptions &opt);
std::string frames_csv(const TrackStatsResult &r);

/// A 2x2 panel PNG: tracked count and new-feature share per frame, track-length histogram, low-gradient share per
/// frame. Throws DataError naming the file when it cannot be written.
void save_trackstats_plot(const TrackStatsResult &r, const std::string &title, const std::string &png_file);

} // namespace ovton::eval
