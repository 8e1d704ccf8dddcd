#pragma once
// Tracks a dataset's images on a thread of its own, in order, a few images ahead of the filter. The KLT front end
// depends on nothing the filter estimates (it sees only the images), so its work can overlap the filter's
// propagation and update: with the decoding on a third thread, a 2-core machine keeps both cores busy
// (docs/benchmarks.md, "Tracking on its own thread").
#include "ov_core/cam/camera_model.h"
#include "ov_core/track/track_klt.h"
#include "ov_core/types/sensor_data.h"

#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <thread>
#include <vector>

namespace ovton::core {

/// One image as the tracking thread handed it over.
struct TrackedFrame {
  std::vector<TrackedFeature> features;
  double wait_image_ms = 0;      ///< the tracking thread's wait for the decoded image [ms]
  double track_ms = 0;           ///< the tracker's time on this image [ms]
  bool on_caller_thread = false; ///< tracked by take() itself, not on the pipeline's thread (or given)
  std::exception_ptr error;      ///< what getting or tracking the image threw; rethrown by TrackPipeline::take
};

/// The start of a dataset already tracked before the replay (the coarse t_d search's window, tracked with the filter's
/// tracker options): the features of images 0 .. frames.size() - 1 and the tracker as it was after the last of them,
/// to go on from. Tracking them again would give the same features.
struct TrackedStart {
  std::vector<std::vector<TrackedFeature>> frames;
  std::unique_ptr<TrackKLT> tracker;
};

class TrackPipeline {
public:
  /// Gives the decoded image of images[index]; called on the tracking thread, for index 0, 1, 2, ... in turn. It may
  /// throw (unreadable file, wrong size): the error is handed to the consumer with that image.
  using ImageGetter = std::function<cv::Mat(size_t index)>;

  /// Starts tracking images[0], images[1], ... with at most `ahead` tracked images waiting. `images` must outlive the
  /// pipeline and hold image entries only (a feature-level dataset has no tracking to overlap).
  TrackPipeline(const std::vector<ImageEntry> &images, const CameraModel &camera, const TrackKLTOptions &opt,
                ImageGetter get_image, size_t ahead = 2);
  /// Hands out start.frames as given, then tracks on from image start.frames.size() with start.tracker. Without a
  /// thread (`threaded` false) take() tracks on the caller's thread: the given start is then all it saves.
  TrackPipeline(const std::vector<ImageEntry> &images, TrackedStart start, ImageGetter get_image, bool threaded,
                size_t ahead = 2);
  ~TrackPipeline();
  TrackPipeline(const TrackPipeline &) = delete;
  TrackPipeline &operator=(const TrackPipeline &) = delete;

  /// The tracked features of images[index], waiting for them if need be; rethrows what getting or tracking that image
  /// threw. Indices must increase between calls. The thread tracks every image of the list, so an image the consumer
  /// skips is still tracked through (as a sequential run would not: the replay only skips images after the end of
  /// the IMU log, where nothing follows that it processes). Throws std::logic_error for an index not after the last
  /// one taken or outside the list.
  TrackedFrame take(size_t index);
  /// The same for an entry of the list (the replay hands out the list's own entries).
  TrackedFrame take(const ImageEntry &e);

private:
  void work();
  TrackedFrame track_caught(size_t index);
  /// Tracks the next image: called with the lock held, released while tracking. The thread's loop body, and take()'s
  /// when there is no thread.
  void produce_locked(std::unique_lock<std::mutex> &lock);

  const std::vector<ImageEntry> &images_;
  std::vector<std::vector<TrackedFeature>> given_; ///< images tracked before, handed out as they are
  const bool threaded_;
  std::unique_ptr<TrackKLT> tracker_; ///< used by the tracking thread only (or take's caller without one)
  const ImageGetter get_image_;
  const size_t ahead_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::map<size_t, TrackedFrame> ready_; ///< tracked, not yet taken
  size_t next_take_ = 0;                 ///< lowest index the consumer may still ask for
  size_t produced_ = 0;                  ///< images the thread has finished
  bool failed_ = false;                  ///< the thread stopped at an error (handed out with its image)
  std::exception_ptr failure_;           ///< that error, for a consumer that skipped its image
  bool stop_ = false;
  std::thread thread_; // last: started once everything above is constructed; none when not threaded
};

} // namespace ovton::core
