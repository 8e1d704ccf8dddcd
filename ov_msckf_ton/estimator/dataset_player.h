#pragma once
// A recording (EuRoC or SCube folder, ROS bag, simulation) played into an Estimator as a live system would receive it:
// IMU readings and images merged by their stamps, each image decoded just before it is fed. `ovton run`, `compare`,
// `benchmark` and the tests play recordings this way; a robot program feeds its own sensors instead.
#include "ov_core/io/dataset.h"
#include "ov_msckf_ton/estimator/estimator.h"

#include <cstddef>
#include <functional>

namespace ovton {

/// The recording's own facts where the user set none: Kalibr's timeshift_cam_imu as the t_d prior.
void apply_dataset_defaults(const core::Dataset &data, bool td_init_given, msckf::VioOptions &opt);

/// A run over `data` with `opt`: its calibration, its ground truth and true offset as aids, its folder as the source.
EstimatorSetup setup_for(const core::Dataset &data, const msckf::VioOptions &opt);

/// The raw gyro of `data` for a tracker's LK starting points when opt.track.gyro_prior asks for it (else null), looked
/// up at the offset opt.td.init_s (`ovton track`; the estimator keeps its own over the stream).
std::shared_ptr<const core::GyroRotationPrior> rotation_prior_for(const core::Dataset &data,
                                                                  const msckf::VioOptions &opt);

struct PlayOptions {
  long max_images = 0; ///< feed at most this many images (0 or less: all)
  /// Feed at this multiple of real time, each message when its stamp is due (1: as a live system receives them, so
  /// that latencies are a live system's); 0: as fast as the estimator takes them.
  double pace = 0.0;
  /// Called after each image fed with (images fed, images in the recording); false stops the run (an interrupt): the
  /// estimator is stopped rather than finished.
  std::function<bool(size_t, size_t)> on_progress;
};

struct PlayResult {
  size_t imu_fed = 0, images_fed = 0;
  double decode_ms = 0;     ///< spent decoding images (on the caller's thread)
  double wall_s = 0;        ///< from the first feed to the end of finish()
  double data_span_s = 0;   ///< camera time covered by the images fed
  bool interrupted = false; ///< on_progress stopped it
};

/// Feeds `data` into `est` and finishes it. What the estimator throws passes through (an unreadable image as
/// DataError naming its file; EstimatorFailure for a diverged estimate), after the states before it were handed out.
/// With max_images the IMU is fed to 12 s past the last image fed (|t_d| is at most 10 s, and the filter looks ahead).
/// A recording cut short (Dataset::truncated_file: a recorder that crashed) is played up to the cut and finished, then
/// DataError names the file and the byte of the cut (core::check_not_truncated): its states were handed out first.
PlayResult play(const core::Dataset &data, Estimator &est, const PlayOptions &opt = {});

} // namespace ovton
