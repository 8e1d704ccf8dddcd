#pragma once
// What every recording writer (`ovton export` to a ROS 1 bag or an MCAP file) does alike: walk a dataset in the order
// a recorder receives it, write to OUT.partial and rename when complete, and put Kalibr files beside the output.
#include "ov_core/io/dataset.h"
#include "ov_core/io/rosbag_writer.h"

#include <opencv2/core.hpp>

#include <functional>
#include <string>
#include <vector>

namespace ovton::core {

/// Images and IMU interleaved in time (IMU clock for the IMU, camera clock for images, as their stamps are), so that a
/// reader streaming the output in time order meets them as a live recording would deliver them: every reading up to
/// an image's stamp, then the image with its pixels, then the further cameras' images up to that stamp (`camera`:
/// 0 the primary, k the dataset's more_cameras[k - 1]). progress(i, n) after each primary image; returning false
/// stops with UsageError naming `partial`. Throws UsageError for a feature-level dataset (no pixels) and DataError for
/// an unreadable image.
void walk_for_export(const Dataset &d, const std::function<void(const ImuData &)> &on_imu,
                     const std::function<void(const ImageEntry &, const cv::Mat &gray, size_t camera)> &on_image,
                     const std::function<bool(size_t, size_t)> &progress, const std::string &partial);

/// The topic of camera k of an export whose primary camera is on `cam0_topic`: "cam0" in it replaced by "camK" (the
/// EuRoC bags' /cam1/image_raw), else "_camK" appended.
std::string export_camera_topic(const std::string &cam0_topic, size_t k);

/// The image form of an export: raw pixels, or a CompressedImage's JPEG or PNG file (image_transport's topic
/// CAM_TOPIC/compressed). Throws UsageError for another format or a JPEG quality outside 1..100.
class CompressedImageEncoder {
public:
  CompressedImageEncoder(const std::string &format, int jpeg_quality);
  bool raw() const { return format_ == "raw"; }
  std::string topic(const std::string &cam_topic) const { return raw() ? cam_topic : cam_topic + "/compressed"; }
  /// The file's bytes; throws DataError naming `path` when the image cannot be encoded.
  std::vector<uint8_t> encode(const cv::Mat &gray, const std::string &path) const;

private:
  std::string format_;
  int quality_;
};

/// Renames `partial` to `out` and sets rep.bytes; with `kalibr`, writes camchain-imucam-STEM.yaml (every camera, with
/// `cam_topics`) and imu-STEM.yaml beside `out` (the names Kalibr gives them, which the readers look for) and sets
/// rep's file names.
void finish_export(const std::string &partial, const std::string &out, const Dataset &d, bool kalibr,
                   const std::vector<std::string> &cam_topics, const std::string &imu_topic, BagWriteReport &rep);

} // namespace ovton::core
