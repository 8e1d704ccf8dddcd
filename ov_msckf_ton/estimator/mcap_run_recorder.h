#pragma once
// A run written as Foxglove shows it (core::RunMcapWriter: the image with its features' fate, the estimated and true
// pose, tf, the paths, t_d ± σ) from what the estimator hands out — each image as tracked (encoded there, so that only
// its JPEG waits for the filter), its features' fate after the filter (an observer) and each state (a callback).
// `ovton run --mcap-out` attaches one; a program that embeds the Estimator does the same:
//   auto rec = ovton::McapRunRecorder::attach(est, "run.mcap");   // before the first feed
//   ... feed ..., est.finish();
//   rec->close();                                                  // the summary: Foxglove's index
// The file grows as the run goes (a chunk every McapWriteOptions::chunk_size bytes, flushed to the file); a run that
// stops early (Ctrl-C, an error) still closes it whole, and a process that is killed leaves the chunks written so
// far, which a reader walking the data section (ovton's, Foxglove's for an unindexed file) reads.
#include "ov_core/io/run_mcap_writer.h"
#include "ov_msckf_ton/core/filter_observer.h"
#include "ov_msckf_ton/estimator/estimator.h"

#include <map>
#include <memory>
#include <mutex>
#include <string>

namespace ovton {

class McapRunRecorder : public msckf::FilterObserver {
public:
  /// Creates `path` (DataError naming it when it cannot be written).
  explicit McapRunRecorder(const std::string &path, const core::RunMcapOptions &opt = {});
  /// A recorder attached to `est` before its first feed: its observer and a state callback.
  static std::shared_ptr<McapRunRecorder> attach(Estimator &est, const std::string &path,
                                                 const core::RunMcapOptions &opt = {});

  /// Ground truth and the true t_d (RunMcapWriter::set_truth), before the first feed.
  void set_truth(std::vector<core::StateSample> groundtruth, std::vector<core::TdSample> td_truth);
  /// On the tracking thread: the image's message, kept until its on_frame.
  void on_image(int64_t t_cam_ns, const cv::Mat &gray) override;
  /// On the filter thread: the image's message (dropping those of images the filter never processed) and its features.
  void on_frame(const msckf::FrameFeatures &frame) override;
  void on_state(const core::StateSample &s);
  /// After the estimator's finish() or stop(): the last path and the summary. Throws DataError when the file cannot
  /// be written. (The destructor closes an unclosed file too, swallowing errors.)
  void close();
  std::vector<std::pair<std::string, uint64_t>> message_counts() const { return writer_.message_counts(); }

private:
  core::RunMcapWriter writer_;
  std::mutex pending_m_;
  std::map<int64_t, std::vector<uint8_t>> pending_; ///< encoded images by camera stamp, waiting for the filter
  std::vector<core::RunFeature> features_;          ///< reused from image to image
};

} // namespace ovton
