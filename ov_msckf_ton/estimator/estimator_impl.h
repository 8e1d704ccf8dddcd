#pragma once
// The estimator's insides (estimator.h): the shared queues and the two stages that work on them. One mutex guards the
// queues and the status; each stage owns its own tools (the tracking stage its tracker, gyro prior and search, the
// filter stage its VioManager) and does its heavy work with the mutex released.
#include "ov_core/cam/camera_model.h"
#include "ov_core/track/track_klt.h"
#include "ov_core/track/track_stereo.h"
#include "ov_core/types/imu_buffer.h"
#include "ov_msckf_ton/estimator/estimator.h"

#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>

namespace ovton {

class Estimator::Impl {
public:
  explicit Impl(EstimatorSetup setup);
  ~Impl();

  void add_state_callback(StateCallback cb);
  void add_observer(std::shared_ptr<msckf::FilterObserver> observer);
  void feed_imu(const core::ImuData &m);
  void feed_image(int64_t t_cam_ns, const cv::Mat &gray, std::vector<core::PointObservation> observations,
                  bool feature_level, std::vector<cv::Mat> more = {});
  size_t poll(std::vector<core::StateSample> &out);
  size_t camera_count() const { return 1 + setup_.more_cameras.size(); }
  EstimatorStatus status() const;
  void finish();
  void stop();
  EstimatorReport report() const;

private:
  using Clock = std::chrono::steady_clock;
  using Lock = std::unique_lock<std::mutex>;
  /// An image as fed, waiting to be tracked.
  struct Input {
    int64_t t_cam_ns;
    cv::Mat gray;
    std::vector<cv::Mat> more;                        ///< the rig's further cameras' images (empty: none)
    std::vector<core::PointObservation> observations; ///< a feature-level image's points
    bool feature_level;
    Clock::time_point arrived;
  };
  /// An image's features, waiting for the filter.
  struct Tracked {
    int64_t t_cam_ns;
    std::vector<core::TrackedFeature> features;
    std::vector<std::vector<core::TrackedFeature>> more; ///< the rig's further cameras', by camera - 1
    Clock::time_point arrived;
  };

  // --- the stages; each is called with the lock held, returns whether it did anything, and may release the lock
  // while it works.
  bool track_step(Lock &lk);
  bool filter_step(Lock &lk);
  /// Runs both stages on the caller's thread until neither can go on (unthreaded).
  void pump(Lock &lk);
  void stage_loop(bool tracking);
  /// An exception from a stage: the run stops, and the feed calls and finish() rethrow it.
  void fail(Lock &lk, std::exception_ptr e);
  void rethrow_if_failed() const;
  void start_first_feed(Lock &lk);

  // tracking stage
  /// Hands the tracking stage's IMU consumers (search, gyro prior) every reading up to the first one after t_imu_ns;
  /// false (handing nothing) while that reading has not arrived and the stream goes on.
  bool imu_past_for_tracking(Lock &lk, int64_t t_imu_ns);
  std::vector<core::TrackedFeature> track(const Input &in);
  /// The further cameras' features of an image `track` has just tracked in the primary.
  std::vector<std::vector<core::TrackedFeature>> track_more(const Input &in);
  /// The coarse search has decided: the filter's t_d prior, the gyro prior's offset, the held images to the filter.
  void release_search(Lock &lk);
  bool tracking_uses_imu() const { return (search_ && !search_->done()) || prior_on_; }

  // filter stage
  void on_state(const core::StateSample &s);
  /// Forgets the readings both stages are past.
  void trim_imu();

  EstimatorSetup setup_;
  core::CameraModel camera_;
  std::vector<StateCallback> callbacks_;
  std::vector<std::shared_ptr<msckf::FilterObserver>> observers_;

  mutable std::mutex m_;
  std::condition_variable cv_;
  std::deque<core::ImuData> imu_; ///< received and not yet passed by both stages
  size_t imu_base_ = 0;           ///< index (since the start) of imu_.front()
  std::deque<Input> inputs_;
  std::deque<Tracked> tracked_; ///< for the filter
  int64_t last_image_ns_ = 0, last_imu_ns_ = 0;
  bool started_ = false, eos_ = false, stopping_ = false;
  bool search_done_ = false, tracking_done_ = false, filter_done_ = false;
  bool track_waits_imu_ = false, filter_waits_imu_ = false;
  std::exception_ptr error_;
  EstimatorStatus status_;
  std::deque<core::StateSample> polled_;
  std::vector<double> latency_ms_;

  // owned by the tracking stage
  size_t track_imu_next_ = 0; ///< next reading (index since the start) for the search and the gyro prior
  bool track_imu_handed_ = false;
  int64_t track_last_handed_ns_ = 0;
  std::unique_ptr<core::TrackKLT> tracker_;
  std::vector<std::unique_ptr<core::TrackSecondary>> secondary_; ///< the rig's further cameras
  bool prior_on_ = false;
  std::shared_ptr<core::ImuBuffer> prior_imu_;
  Eigen::Matrix3d R_IC_ = Eigen::Matrix3d::Identity();
  int64_t prior_td_ns_ = 0;
  std::unique_ptr<msckf::TdSearch> search_;
  std::deque<Tracked> held_; ///< tracked while the search decides
  double tracking_ms_ = 0;

  // owned by the filter stage
  msckf::VioOptions filter_opt_; ///< the options; the search's t_d once it has decided
  std::unique_ptr<msckf::VioManager> vio_;
  size_t filter_imu_next_ = 0; ///< next reading (index since the start) for the filter
  bool filter_fed_any_ = false;
  int64_t filter_last_fed_ns_ = 0;
  Clock::time_point current_arrival_;

  std::thread track_thread_, filter_thread_;
};

} // namespace ovton
