#pragma once
// Monocular KLT front end, as OpenVINS' TrackKLT: grid-based FAST detection, pyramidal Lucas-Kanade tracking on
// pyramids built once per image, RANSAC on the fundamental matrix in undistorted normalised coordinates.
#include "ov_core/cam/camera_model.h"
#include "ov_core/track/gyro_prior.h"
#include "ov_core/track/lk_flow.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace ovton::core {

enum class ImageEqualization { None, Histogram, Clahe };

struct TrackKLTOptions {
  int num_features = 200; ///< target number of tracked features per frame
  int grid_x = 8;         ///< detection grid columns; each cell is filled up to num_features / (grid_x * grid_y)
  int grid_y = 5;
  int min_px_dist = 10;    ///< minimum distance between a new feature and any other [px]
  int fast_threshold = 20; ///< FAST intensity threshold
  /// Fraction of num_features below which detection runs. Detection on a nearly full set costs a FAST pass for
  /// a handful of points; tracks that drop a few features wait until more are missing.
  double detect_below_fraction = 0.95;
  /// No detection this close to the image border: half the LK window, so that a new feature's window lies in the
  /// image (a window hanging over the border sees padding that moves with the image edge, not with the scene).
  int border_px = 10;

  int win_size = 21;  ///< LK window side [px]
  int pyr_levels = 3; ///< OpenCV maxLevel, as OpenVINS' pyr_levels: the pyramid holds pyr_levels + 1 images
  int lk_max_iter = 30;
  double lk_eps = 0.01; ///< LK stops when the update is below this [px]
  /// Start LK where the gyro's rotation takes each point (when the tracker is given a GyroRotationPrior); the
  /// pyramid then only has to find the parallax.
  bool gyro_prior = false;
  bool forward_backward = false;
  double fb_max_px = 0.5; ///< forward-backward round trip error above which a track is dropped [px]

  bool use_ransac = true;
  double ransac_px = 1.0; ///< epipolar distance threshold [px]; divided by the larger focal length for RANSAC
  double ransac_confidence = 0.999;

  ImageEqualization equalization = ImageEqualization::Histogram;
  double clahe_clip = 3.0;
  int clahe_tiles = 8;
};

/// An image as the trackers work on it: equalised as the options say, and its pyramid for lk_flow (built once per
/// image). Shared by the primary camera's tracker and a rig's further cameras (track_stereo.h).
class LkImagePreparer {
public:
  explicit LkImagePreparer(const TrackKLTOptions &opt);
  /// Equalises `gray` into `img` (a copy when equalisation is off: the pyramid must outlive the caller's buffer).
  void equalize(const cv::Mat &gray, cv::Mat &img) const;
  void build_pyramid(const cv::Mat &img, LkPyramid &out);
  /// lk_flow's parameters for the options (no initial guess).
  LkParams lk_params() const;

private:
  TrackKLTOptions opt_;
  cv::Ptr<cv::CLAHE> clahe_;
  std::vector<cv::Mat> pyr_; // OpenCV's 8-bit pyramid, from which the float planes are made
};

/// One feature in one frame, as the tracker hands it to the feature database.
struct TrackedFeature {
  size_t id = 0;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero(); ///< distorted pixel
  Eigen::Vector2d xy = Eigen::Vector2d::Zero(); ///< undistorted normalised
};

/// Per-frame cost and counts. Times are wall clock [ms] of the last frame; totals accumulate over frames.
struct TrackStats {
  double t_equalize_ms = 0, t_pyramid_ms = 0, t_tracking_ms = 0, t_undistort_ms = 0, t_ransac_ms = 0;
  double t_detection_ms = 0, t_total_ms = 0;
  int num_prev = 0;            ///< features entering the frame
  int num_lk_lost = 0;         ///< LK failed or left the image
  int num_fb_rejected = 0;     ///< forward-backward check failed
  int num_ransac_rejected = 0; ///< RANSAC outliers
  int num_merged = 0;          ///< dropped because another, older track is at the same place
  int num_detected = 0;        ///< new features this frame
  int num_features = 0;        ///< features output this frame
};

struct TrackStatsTotals {
  long frames = 0;
  double t_equalize_ms = 0, t_pyramid_ms = 0, t_tracking_ms = 0, t_undistort_ms = 0, t_ransac_ms = 0;
  double t_detection_ms = 0, t_total_ms = 0;
  /// Mean per-frame cost of one stage, e.g. totals.mean(totals.t_tracking_ms).
  double mean(double total_ms) const { return frames > 0 ? total_ms / static_cast<double>(frames) : 0.0; }
  void add(const TrackStats &s);
};

/// RANSAC on the fundamental matrix between two sets of undistorted normalised points. Writes 1 (inlier) or 0
/// per correspondence into `inlier` and returns the number of inliers. Inliers are classified against the F refitted
/// on RANSAC's consensus (distance to the epipolar line in both views), not the minimal sample's F. With fewer than
/// 8 correspondences, or no model, every point is kept (too few to tell). `thresh_norm`: distance in normalised units.
int ransac_fundamental(const std::vector<cv::Point2f> &xy0, const std::vector<cv::Point2f> &xy1, double thresh_norm,
                       double confidence, std::vector<unsigned char> &inlier);

class TrackKLT {
public:
  TrackKLT(const TrackKLT &) = delete; // a copy would share the pyramid's pixels
  TrackKLT &operator=(const TrackKLT &) = delete;
  /// Throws UsageError for options that cannot work (non-positive sizes, even LK window, ...).
  TrackKLT(const CameraModel &camera, const TrackKLTOptions &opt = {});

  /// Tracks the previous frame's features into `gray` (8-bit, one channel, the camera's size), drops outliers,
  /// tops the set up with new detections and returns every feature seen in this frame. The reference stays valid
  /// until the next call. Throws UsageError on a wrong image type/size or a stamp not after the previous one.
  const std::vector<TrackedFeature> &track(int64_t t_cam_ns, const cv::Mat &gray);

  /// The raw gyro, for options().gyro_prior (shared: the estimator swaps it when the coarse t_d search has decided).
  void set_rotation_prior(std::shared_ptr<const GyroRotationPrior> prior) { prior_ = std::move(prior); }

  /// Forgets all tracks (e.g. after a gap in the data); ids keep increasing so they never repeat.
  void reset();

  const std::vector<TrackedFeature> &current() const { return out_; }
  const TrackStats &last_stats() const { return stats_; }
  const TrackStatsTotals &totals() const { return totals_; }
  const TrackKLTOptions &options() const { return opt_; }
  /// The image the tracker worked on (after equalisation), for visualisation.
  const cv::Mat &last_image() const { return img_; }
  /// The pyramid of the last image tracked (a rig's further cameras match into their images from it).
  const LkPyramid &last_pyramid() const { return lk_prev_; }
  const CameraModel &camera() const { return camera_; }

private:
  void track_previous(int64_t t_cam_ns);
  void merge_and_detect();
  /// Drops features i with keep[i] == 0 from the parallel per-feature arrays.
  void compact(const std::vector<unsigned char> &keep);

  CameraModel camera_;
  TrackKLTOptions opt_;
  LkImagePreparer prep_;
  std::shared_ptr<const GyroRotationPrior> prior_;

  bool has_prev_ = false;
  int64_t t_prev_ns_ = 0;
  size_t next_id_ = 0;

  cv::Mat img_;
  LkPyramid lk_prev_, lk_curr_; // swapped each frame so the pyramid is built once per image

  // Per-feature state, parallel arrays in id order (older tracks first, which detection prefers to keep).
  std::vector<size_t> ids_;
  std::vector<cv::Point2f> pts_;
  std::vector<Eigen::Vector2d> xy_;

  // Scratch, kept across frames so that a frame allocates nothing once the sizes have settled.
  std::vector<cv::Point2f> pts_next_, pts_back_, xy0f_, xy1f_;
  std::vector<Eigen::Vector2d> xy_next_;
  std::vector<unsigned char> status_, status_back_, keep_;
  std::vector<cv::KeyPoint> keypoints_, cell_kp_;
  std::vector<int> cell_count_;
  cv::Mat mask_;
  cv::Mat grid_occ_;
  std::vector<TrackedFeature> out_;

  TrackStats stats_;
  TrackStatsTotals totals_;
};

} // namespace ovton::core
