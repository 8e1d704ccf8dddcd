#include "ov_core/io/rosbag_writer.h"
#include "ov_core/io/recording_export.h"
#include "ov_core/io/rosbag_messages.h"
#include "ov_core/types/errors.h"

#include <rosbag/bag.h>

namespace ovton::core {

namespace {

rosbag::compression::CompressionType parse_compression(const std::string &s) {
  if (s == "none")
    return rosbag::compression::Uncompressed;
  if (s == "bz2")
    return rosbag::compression::BZ2;
  if (s == "lz4")
    return rosbag::compression::LZ4;
  throw UsageError("unknown bag compression '" + s + "' (expected none, bz2 or lz4)");
}

} // namespace

BagWriteReport write_bag(const Dataset &d, const std::string &out, const BagWriteOptions &opt,
                         const std::function<bool(size_t, size_t)> &progress) {
  const auto compression = parse_compression(opt.compression);
  const CompressedImageEncoder encoder(opt.image_format, opt.jpeg_quality);
  const std::string partial = out + ".partial";
  std::vector<std::string> cam_topics; // the primary's, then each further camera's (a stereo folder's cam1)
  for (size_t k = 0; k < d.num_cameras(); ++k)
    cam_topics.push_back(encoder.topic(export_camera_topic(opt.cam_topic, k)));
  BagWriteReport rep;
  try {
    rosbag::Bag bag(partial, rosbag::bagmode::Write);
    bag.setCompression(compression);
    walk_for_export(
        d,
        [&](const ImuData &u) {
          const auto m = imu_to_message(u, "imu0");
          bag.write(opt.imu_topic, m.header.stamp, m);
          ++rep.imu;
        },
        [&](const ImageEntry &e, const cv::Mat &gray, size_t camera) {
          const std::string frame = "cam" + std::to_string(camera);
          if (encoder.raw()) {
            const auto m = gray_to_message(gray, e.t_cam_ns, frame);
            bag.write(cam_topics[camera], m.header.stamp, m);
          } else {
            sensor_msgs::CompressedImage m;
            m.header.stamp = to_ros_time(e.t_cam_ns);
            m.header.frame_id = frame;
            m.format = opt.image_format;
            m.data = encoder.encode(gray, e.path);
            bag.write(cam_topics[camera], m.header.stamp, m);
          }
          rep.images += camera == 0; // the primary's images, as the progress counts them
        },
        progress, partial);
    bag.close();
  } catch (const ros::Exception &e) {
    throw DataError(partial, std::string("writing the bag failed: ") + e.what());
  }
  finish_export(partial, out, d, opt.kalibr_files, cam_topics, opt.imu_topic, rep);
  return rep;
}

} // namespace ovton::core
