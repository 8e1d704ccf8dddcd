#pragma once
// One replay of a dataset through the estimator, shared by `run`, `compare` and `benchmark`.
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_prefetcher.h"
#include "ov_core/io/replay.h"
#include "ov_eval/nees.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_msckf_ton/init/td_search.h"

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ovton::cli {

struct RunRequest {
  ovton::msckf::VioOptions opt;
  std::string output;       ///< trajectory file ("" = none)
  bool tum = false;         ///< TUM text instead of the project CSV
  std::string residual_log; ///< "" = none
  std::string velocity_log; ///< "" = none (see ov_core/io/velocity_log.h)
  long max_images = 0;      ///< 0 = all
  bool progress = true;     ///< progress bar on stderr
  std::string label;        ///< progress bar label
  /// Decode the next images on a second thread (ovton::core::ImagePrefetcher) while the filter works. Same results;
  /// `image_load` then measures the wait for a decoded image.
  bool prefetch = false;
  /// With prefetch, track the images on a third thread (ovton::core::TrackPipeline), overlapping the filter's update.
  /// Same results; `image_load` then measures the wait for a tracked image.
  bool track_thread = true;
  /// When the coarse t_d search's window starts at the first image, the filter takes its tracks of that window instead
  /// of tracking the images again (the search tracks them with the filter's options). Same results.
  bool reuse_search_tracks = true;
  /// Called after each image with (images done, images in the dataset); the benchmark samples memory here.
  std::function<void(size_t, size_t)> on_progress;
  /// The coarse t_d search keeps up to this many bytes of the images it decodes (8 s at 20 Hz of 752x480 is 58 MB) and
  /// the filter takes them instead of decoding them again; 0: decoded twice.
  size_t keep_search_images_bytes = kKeepSearchImagesBytes;
  /// Images decoded before this run (`compare`: by the search its modes share); the run's own search keeps none then.
  std::shared_ptr<const ovton::core::DecodedImages> decoded;
  /// The first images' tracks made before this run with opt.track (`compare`: by the search its modes share): the run
  /// takes a copy and goes on from a clone of its tracker.
  std::shared_ptr<const ovton::core::TrackedStart> tracked;
  static constexpr size_t kKeepSearchImagesBytes = size_t{128} << 20;
};

struct RunResult {
  std::vector<ovton::core::StateSample> traj;
  ovton::msckf::VioCounters counters;
  ovton::msckf::StageTimes times;
  ovton::eval::NeesStats nees; ///< counted with ground-truth initialisation only (the estimate is in its frame)
  ovton::core::ReplayStats replay;
  std::string init_message;
  ovton::msckf::UpdateTally acceptance;                  ///< features used / gated / failed triangulation over the run
  std::optional<ovton::msckf::TdSearchResult> td_search; ///< when the coarse search ran
  size_t images_predecoded = 0; ///< images the filter took decoded (by the search) instead of decoding them
  size_t images_pretracked = 0; ///< images whose tracks the filter took from the search instead of tracking them
  double wall_s = 0.0;
  double data_span_s = 0.0; ///< camera time covered by the images replayed
  bool interrupted = false;
};

/// Runs the estimator over `data` as asked. Rows are written (and flushed) as they are produced. Runs the coarse t_d
/// search first when req.opt asks for it (run_td_search). Throws ovton::core::EstimatorFailure when the filter's health
/// check fails (the rows before it stay on disk) and DataError when the run ends without a single pose.
RunResult run_dataset(const ovton::core::Dataset &data, const RunRequest &req);

/// The coarse t_d search (ov_msckf_ton/init/td_search.h) when opt.td_search is set and the mode estimates t_d: on
/// success opt.td_init_s becomes what it found. Either way opt.td_search is cleared, so that the runs of a comparison
/// share one search. Returns nothing when no search was due. With `keep`, the images the search decodes are put there
/// (by index into data.images) while their bytes stay within keep_bytes, for the filter to take instead of decoding
/// them again: the same pixels, so the same trajectory. With `tracked`, the search's tracks when the filter can go on
/// from them (ovton::msckf::search_td); it then keeps no images, since the filter needs none of its window.
/// The raw gyro for the trackers' LK starting points when opt.track.gyro_prior asks for it (else null), looked up at
/// the offset opt.td.init_s.
std::shared_ptr<const ovton::core::GyroRotationPrior> make_rotation_prior(const ovton::core::Dataset &data,
                                                                          const ovton::msckf::VioOptions &opt);

std::optional<ovton::msckf::TdSearchResult> run_td_search(const ovton::core::Dataset &data,
                                                          ovton::msckf::VioOptions &opt,
                                                          ovton::core::DecodedImages *keep = nullptr,
                                                          size_t keep_bytes = RunRequest::kKeepSearchImagesBytes,
                                                          ovton::core::TrackedStart *tracked = nullptr);

/// Applies the dataset's own facts to options the user did not set: Kalibr timeshift as t_d prior.
void apply_dataset_defaults(const ovton::core::Dataset &data, bool td_init_given, ovton::msckf::VioOptions &opt);

} // namespace ovton::cli
