#pragma once
// What the filter shows of its work besides the state: the residuals of each update, the image velocities it used,
// and each image's features with their fate. Logs, `diagnose`, `velocities` and a Foxglove recording are observers; the
// filter calls them on its own thread (on_image alone comes from the tracking stage) and computes the same estimate
// whether any is attached (one exception is said at wants_velocities).
#include "ov_core/io/velocity_log.h"
#include "ov_msckf_ton/update/residual_log.h"

#include <opencv2/core.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace ovton::msckf {

class VioManager; // core/vio_manager.h

/// What became of one image's features in the filter.
struct FrameFeatures {
  enum Fate : unsigned char { Tracked = 0, Used = 1, Gated = 2 };
  int64_t t_cam_ns = 0, t_imu_ns = 0;
  std::vector<size_t> ids;
  std::vector<Eigen::Vector2d> uv; ///< distorted pixels in this image
  /// Used: the feature entered an update at this image (its whole track); Gated: its update refused it (χ² gate,
  /// triangulation); Tracked: still being tracked, or waiting for its update.
  std::vector<Fate> fate;
};

class FilterObserver {
public:
  virtual ~FilterObserver() = default;
  /// Every feature residual of an MSCKF update, with the state after it.
  virtual void on_residuals(const std::vector<ResidualRecord> &records, const State &after) {
    (void)records;
    (void)after;
  }
  /// True to receive on_velocities: then FVON also predicts with the network its rule did not pick (on a copy; the
  /// trajectory is the same, the networks cost more).
  virtual bool wants_velocities() const { return false; }
  /// Per observation of every feature an update uses, each rule's and network's image velocity.
  virtual void on_velocities(const std::vector<ovton::core::VelocityLogRow> &rows) { (void)rows; }
  /// Each image as it is tracked — on the tracking stage's thread (the caller's when not threaded), before it waits for
  /// the coarse t_d search and the filter —, not for a feature-level image. An observer that shows images keeps what
  /// it needs of them here (an encoded copy: the image is the caller's, shared, read-only); on_frame follows for the
  /// images the filter processes, in the same order.
  virtual void on_image(int64_t t_cam_ns, const cv::Mat &gray) {
    (void)t_cam_ns;
    (void)gray;
  }
  /// After each image the filter processed (from its initialisation on), before its state goes to the callbacks.
  virtual void on_frame(const FrameFeatures &frame) { (void)frame; }
  /// After each image, the filter itself, read-only (its state, its networks' statistics): for tests and tools that
  /// look inside. Called on the filter's thread; what it reads is valid only during the call.
  virtual void on_filter(const VioManager &filter) { (void)filter; }
};

/// `ovton run --residual-log`: the residuals and, beside them, the calibration log.
class ResidualLogObserver : public FilterObserver {
public:
  explicit ResidualLogObserver(const std::string &path) : writer_(path) {}
  void on_residuals(const std::vector<ResidualRecord> &records, const State &after) override {
    writer_.write(records, after);
  }

private:
  ResidualLogWriter writer_;
};

/// `ovton run --velocity-log`.
class VelocityLogObserver : public FilterObserver {
public:
  explicit VelocityLogObserver(const std::string &path) : writer_(path) {}
  bool wants_velocities() const override { return true; }
  void on_velocities(const std::vector<ovton::core::VelocityLogRow> &rows) override { writer_.write(rows); }

private:
  ovton::core::VelocityLogWriter writer_;
};

} // namespace ovton::msckf
