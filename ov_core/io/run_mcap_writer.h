#pragma once
// A run as Foxglove shows it (`ovton run --mcap-out RUN.mcap`): an MCAP file in the ros2 profile whose every channel
// has a schema Foxglove and ROS 2 define, so that it opens with no plugin and plays with ros2 bag play.
//   /ovton/image             sensor_msgs/msg/CompressedImage (JPEG) or Image (mono8): the image the filter used
//   /ovton/features          foxglove_msgs/msg/ImageAnnotations: its tracked features, coloured by what the update
//                            did with them (used, gated, tracked only), and a line counting them
//   /ovton/pose              geometry_msgs/msg/PoseStamped: the estimate (frame "world", body = IMU)
//   /ovton/pose_truth        geometry_msgs/msg/PoseStamped: the ground truth at the same times, where known
//   /tf                      tf2_msgs/msg/TFMessage: world -> imu (estimate) and world -> imu_truth
//   /tf_static               tf2_msgs/msg/TFMessage: imu -> cam, when the writer is given T_BC
//   /ovton/path              nav_msgs/msg/Path: the estimated path so far (every path_period_s and at the end)
//   /ovton/path_truth        nav_msgs/msg/Path: the ground truth from the first state on (once, at its time)
//   /ovton/td_ms, /ovton/td_lower_ms, /ovton/td_upper_ms, /ovton/td_truth_ms
//                            std_msgs/msg/Float64: t_d, t_d -/+ its sigma, and the true t_d at each image, in ms
// Every message's log time is the IMU clock (t_imu = t_cam + t_d), so Foxglove's timeline lines them up; an image's
// header stamp and its annotations' are the camera's own stamp (the sensor's time, as in a recording).
#include "ov_core/io/mcap_writer.h"
#include "ov_core/types/sensor_data.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ovton::core {

/// What the filter did with a feature seen in an image.
enum class FeatureStatus : uint8_t {
  Used,   ///< its residual entered an update in this image
  Gated,  ///< its residual was refused by the chi-square gate
  Tracked ///< tracked, not (yet) used in an update
};

struct RunFeature {
  size_t id = 0;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero(); ///< distorted pixel, as tracked
  FeatureStatus status = FeatureStatus::Tracked;
};

struct RunMcapOptions {
  std::string image_format = "jpeg"; ///< jpeg (CompressedImage) | raw (mono8 Image)
  int jpeg_quality = 80;
  double path_period_s = 1.0;          ///< how often (IMU clock) the estimated path is written in full
  std::optional<Eigen::Matrix4d> T_BC; ///< camera -> IMU, for /tf_static (Foxglove then places the image in 3-D)
  McapWriteOptions mcap;
};

class RunMcapWriter {
public:
  /// Creates `path`. Throws DataError naming it when it cannot be written, UsageError for bad options.
  explicit RunMcapWriter(const std::string &path, const RunMcapOptions &opt = {});
  /// Finishes the file when close() was not called (a run stopped by an error still leaves a whole file); errors
  /// there are swallowed, as a destructor must.
  ~RunMcapWriter();
  RunMcapWriter(const RunMcapWriter &) = delete;
  RunMcapWriter &operator=(const RunMcapWriter &) = delete;

  /// Ground truth (IMU clock, sorted; position-only samples give no pose) and the true t_d by camera stamp, before
  /// the first image or state. Either may be empty.
  void set_truth(std::vector<StateSample> groundtruth, std::vector<TdSample> td_truth);
  /// One image as the filter used it: its camera stamp, its IMU-clock time (t_cam + the filter's t_d), the 8-bit gray
  /// pixels (empty for a feature-level recording: then its features alone) and its features.
  void add_image(int64_t t_cam_ns, int64_t t_imu_ns, const cv::Mat &gray, const std::vector<RunFeature> &features);
  /// The /ovton/image message of `gray` (JPEG or mono8, as the options say), to be added later with add_encoded_image.
  /// Touches nothing in the writer: it may run on another thread than the rest (an image encoded when tracked waits for
  /// the filter as its JPEG, not its pixels).
  std::vector<uint8_t> encode_image(int64_t t_cam_ns, const cv::Mat &gray) const;
  /// add_image with the image's message from encode_image (empty: no pixels).
  void add_encoded_image(int64_t t_cam_ns, int64_t t_imu_ns, const std::vector<uint8_t> &image_message,
                         const std::vector<RunFeature> &features);
  /// One estimated state (as written to the trajectory CSV: t_ns in the IMU clock, pose, t_d and its sigma).
  void add_state(const StateSample &s);
  /// Writes the last path and the file's summary. Throws DataError when the file cannot be written.
  void close();

  /// Messages written so far per topic (for a run's summary line and the tests).
  std::vector<std::pair<std::string, uint64_t>> message_counts() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace ovton::core
