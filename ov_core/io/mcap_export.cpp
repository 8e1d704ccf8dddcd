#include "ov_core/io/mcap_export.h"
#include "ov_core/io/recording_export.h"
#include "ov_core/io/ros2_messages.h"
#include "ov_core/io/ros2_schemas.h"
#include "ov_core/types/errors.h"

namespace ovton::core {

namespace {

/// rosbag2's QoS for /tf_static (reliable, transient local, keep last 1), so that a late subscriber of ros2 bag play
/// still gets the transform; other topics leave it empty (rosbag2's defaults).
const char *const kTfStaticQos =
    "- history: 1\n  depth: 1\n  reliability: 1\n  durability: 1\n  deadline:\n"
    "    sec: 2147483647\n    nsec: 4294967295\n  lifespan:\n    sec: 2147483647\n"
    "    nsec: 4294967295\n  liveliness: 1\n  liveliness_lease_duration:\n"
    "    sec: 2147483647\n    nsec: 4294967295\n  avoid_ros_namespace_conventions: false\n";

uint64_t log_time(int64_t t_ns) {
  if (t_ns < 0)
    throw UsageError("stamp " + std::to_string(t_ns) + " ns is negative: MCAP log times are unsigned");
  return static_cast<uint64_t>(t_ns);
}

} // namespace

std::string mcap_export_cam_topic(const McapExportOptions &opt) {
  return CompressedImageEncoder(opt.image_format, opt.jpeg_quality).topic(opt.cam_topic);
}

BagWriteReport write_mcap(const Dataset &d, const std::string &out, const McapExportOptions &opt,
                          const std::function<bool(size_t, size_t)> &progress) {
  const CompressedImageEncoder encoder(opt.image_format, opt.jpeg_quality);
  const bool raw = encoder.raw();
  const std::string partial = out + ".partial";
  std::vector<std::string> cam_topics; // the primary's, then each further camera's (a stereo folder's cam1)
  for (size_t k = 0; k < d.num_cameras(); ++k)
    cam_topics.push_back(encoder.topic(export_camera_topic(opt.cam_topic, k)));
  BagWriteReport rep;
  {
    McapWriter w(partial, opt.mcap);
    const auto channel = [&](const std::string &topic, const std::string &type, const char *qos = "") {
      const uint16_t schema = w.add_schema(type, "ros2msg", ros2_schema(type));
      return w.add_channel(topic, schema, "cdr", {{"offered_qos_profiles", qos}});
    };
    std::vector<uint16_t> cams;
    for (const std::string &topic : cam_topics)
      cams.push_back(channel(topic, raw ? "sensor_msgs/msg/Image" : "sensor_msgs/msg/CompressedImage"));
    const uint16_t info = channel(opt.info_topic, "sensor_msgs/msg/CameraInfo");
    const uint16_t imu = channel(opt.imu_topic, "sensor_msgs/msg/Imu");
    const uint16_t tf = channel("/tf_static", "tf2_msgs/msg/TFMessage", kTfStaticQos);
    if (!d.images.empty() || !d.imu.empty()) {
      Ros2Transform t;
      t.stamp_ns = std::min(d.images.empty() ? INT64_MAX : d.images.front().t_cam_ns,
                            d.imu.empty() ? INT64_MAX : d.imu.front().t_imu_ns);
      t.parent = "imu0";
      t.child = "cam0";
      t.T_parent_child = d.cam.T_BC;
      w.write(tf, log_time(t.stamp_ns), encode_ros2_tf({t}));
    }
    walk_for_export(
        d,
        [&](const ImuData &u) {
          w.write(imu, log_time(u.t_imu_ns), encode_ros2_imu(u, "imu0"));
          ++rep.imu;
        },
        [&](const ImageEntry &e, const cv::Mat &gray, size_t camera) {
          const uint64_t t = log_time(e.t_cam_ns);
          const std::string frame = "cam" + std::to_string(camera);
          if (raw) {
            w.write(cams[camera], t, encode_ros2_image(gray, e.t_cam_ns, frame));
          } else {
            w.write(cams[camera], t,
                    encode_ros2_compressed_image(encoder.encode(gray, e.path), opt.image_format, e.t_cam_ns, frame));
          }
          if (camera > 0) // the further cameras' calibration is in the Kalibr files beside the export
            return;
          w.write(info, t, encode_ros2_camera_info(d.cam, e.t_cam_ns, "cam0"));
          ++rep.images;
        },
        progress, partial);
    w.close();
  }
  finish_export(partial, out, d, opt.kalibr_files, cam_topics, opt.imu_topic, rep);
  return rep;
}

} // namespace ovton::core
