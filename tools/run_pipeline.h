#pragma once
// One run of a recording through the estimator as the command line does it (`run`, `compare`, `benchmark`): the
// library's Estimator fed by its player (ov_msckf_ton/estimator), with the outputs the user asked for — trajectory
// file, residual and velocity logs, NEES against the ground truth — attached as callbacks and observers, and a progress
// bar.
#include "ov_core/io/dataset.h"
#include "ov_core/io/run_mcap_writer.h"
#include "ov_eval/nees.h"
#include "ov_msckf_ton/estimator/dataset_player.h"
#include "ov_msckf_ton/estimator/estimator.h"

#include <functional>
#include <memory>
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
  /// Track and filter on threads of their own while the next image is decoded here (EstimatorSetup::threaded); false:
  /// everything on this thread. Same results.
  bool threaded = true;
  /// Feed at this multiple of real time (PlayOptions::pace; 0: as fast as it goes).
  double pace = 0.0;
  /// More observers of the filter.
  std::vector<std::shared_ptr<ovton::msckf::FilterObserver>> observers;
  /// The run as Foxglove shows it (ovton::McapRunRecorder; "" = none), with the recording's truth and T_BC.
  std::string mcap_out;
  ovton::core::RunMcapOptions mcap;
  /// Called after each image fed with (images fed, images in the dataset); the benchmark samples memory here.
  std::function<void(size_t, size_t)> on_progress;
};

struct RunResult {
  std::vector<ovton::core::StateSample> traj;
  ovton::EstimatorReport report;
  ovton::PlayResult play;
  ovton::eval::NeesStats nees; ///< counted with ground-truth initialisation only (the estimate is in its frame)
  std::vector<std::pair<std::string, uint64_t>> mcap_counts; ///< messages per topic in mcap_out
};

/// Runs the estimator over `data` as asked; rows are written (and flushed) as they come out. Throws
/// ovton::core::EstimatorFailure when the filter's health check fails (the rows before it stay on disk) and DataError
/// when the run ends without a single pose.
RunResult run_dataset(const ovton::core::Dataset &data, const RunRequest &req);

} // namespace ovton::cli
