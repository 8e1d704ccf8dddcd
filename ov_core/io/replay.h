#pragma once
// Time-ordered replay of a dataset: all IMU readings up to an image's IMU-clock time, then the image.
#include "ov_core/io/dataset.h"
#include "ov_core/types/sensor_data.h"

#include <cstddef>
#include <functional>
#include <vector>

namespace ovton::core {

/// What the replay feeds. td_for_image_s(t_cam) is asked before each image: the consumer's current t_d for it
/// decides how much IMU it needs (t_imu = t_cam + t_d), so the replay never hands it an image it cannot propagate to.
class ReplayConsumer {
public:
  virtual ~ReplayConsumer() = default;
  virtual void on_imu(const ImuData &imu) = 0;
  virtual void on_image(const ImageEntry &img) = 0;
  virtual double td_for_image_s(int64_t t_cam_ns) const = 0;
  /// How far past an image's IMU-clock time the consumer wants the readings before the image (a centred estimate of
  /// the body rate at the image needs some; a live system pays it as latency).
  virtual int64_t imu_lookahead_ns() const { return 0; }
};

struct ReplayStats {
  size_t imu_fed = 0;
  size_t images_fed = 0;
  size_t images_skipped = 0; ///< images whose IMU-clock time lies beyond the last IMU reading
};

class Replay {
public:
  explicit Replay(const Dataset &d) : images_(d.images), imu_(d.imu), dataset_(&d) {}
  Replay(const std::vector<ImageEntry> &images, const std::vector<ImuData> &imu) : images_(images), imu_(imu) {}

  /// progress(i, n) is called after each image; returning false stops the replay early (e.g. on SIGINT). A dataset
  /// that ends in a cut (Dataset::truncated_file) throws DataError naming it once its last image has been fed.
  ReplayStats run(ReplayConsumer &c, const std::function<bool(size_t, size_t)> &progress = {}) const;

private:
  const std::vector<ImageEntry> &images_;
  const std::vector<ImuData> &imu_;
  const Dataset *dataset_ = nullptr;
};

} // namespace ovton::core
