#pragma once
// A dataset written as an MCAP file in the ros2 profile (`ovton export --format mcap`), as a ROS 2 user's recording
// holds it and `ros2 bag play` replays it: sensor_msgs/msg/Image (mono8) or CompressedImage (JPEG or PNG) on the camera
// topic, sensor_msgs/msg/Imu, the camera's CameraInfo with every image and the camera-IMU extrinsics on /tf_static, all
// in CDR with their message definitions; header stamps (and log times) from the dataset.
#include "ov_core/io/dataset.h"
#include "ov_core/io/mcap_writer.h"
#include "ov_core/io/rosbag_writer.h"

#include <functional>
#include <string>

namespace ovton::core {

struct McapExportOptions {
  std::string cam_topic = "/cam0/image_raw"; ///< compressed images go to CAM_TOPIC/compressed (image_transport's name)
  std::string imu_topic = "/imu0";
  std::string info_topic = "/cam0/camera_info";
  std::string image_format = "raw"; ///< raw (mono8 Image) | jpeg | png (CompressedImage)
  int jpeg_quality = 95;
  McapWriteOptions mcap;
  bool kalibr_files = true; ///< also camchain-imucam-STEM.yaml and imu-STEM.yaml beside the file (write_bag's)
};

/// Writes `d` (a folder with images) to `out` via OUT.partial, renamed when complete; progress as write_bag's.
BagWriteReport write_mcap(const Dataset &d, const std::string &out, const McapExportOptions &opt = {},
                          const std::function<bool(size_t, size_t)> &progress = {});

/// The image topic write_mcap uses for `opt` (CAM_TOPIC or CAM_TOPIC/compressed).
std::string mcap_export_cam_topic(const McapExportOptions &opt);

} // namespace ovton::core
