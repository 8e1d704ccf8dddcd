#include "ov_core/io/rosbag_writer.h"
#include "ov_core/io/image_store.h"
#include "ov_core/io/kalibr_writer.h"
#include "ov_core/io/rosbag_messages.h"
#include "ov_core/types/errors.h"

#include <rosbag/bag.h>

#include <filesystem>

namespace fs = std::filesystem;

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
  if (!d.images.empty() && d.images.front().features)
    throw UsageError(d.root + " is a feature-level dataset (cam0/features.csv): it has no images to write to a bag");
  const auto compression = parse_compression(opt.compression);
  const std::string partial = out + ".partial";
  BagWriteReport rep;
  try {
    rosbag::Bag bag(partial, rosbag::bagmode::Write);
    bag.setCompression(compression);
    // Images and IMU interleaved in time (IMU clock for the IMU, camera clock for images, as their stamps are), so that
    // a reader streaming the bag in time order meets them as a live recording would deliver them.
    size_t k = 0;
    for (size_t i = 0; i < d.images.size(); ++i) {
      const ImageEntry &e = d.images[i];
      for (; k < d.imu.size() && d.imu[k].t_imu_ns <= e.t_cam_ns; ++k, ++rep.imu) {
        const auto m = imu_to_message(d.imu[k], "imu0");
        bag.write(opt.imu_topic, m.header.stamp, m);
      }
      const cv::Mat gray = load_image(e);
      if (gray.empty())
        throw DataError(e.path, "unreadable image (listed for stamp " + std::to_string(e.t_cam_ns) + ")");
      const auto m = gray_to_message(gray, e.t_cam_ns, "cam0");
      bag.write(opt.cam_topic, m.header.stamp, m);
      ++rep.images;
      if (progress && !progress(i + 1, d.images.size()))
        throw UsageError("export interrupted: " + partial + " left incomplete");
    }
    for (; k < d.imu.size(); ++k, ++rep.imu) {
      const auto m = imu_to_message(d.imu[k], "imu0");
      bag.write(opt.imu_topic, m.header.stamp, m);
    }
    bag.close();
  } catch (const ros::Exception &e) {
    throw DataError(partial, std::string("writing the bag failed: ") + e.what());
  }
  std::error_code ec;
  fs::rename(partial, out, ec);
  if (ec)
    throw DataError(out, "cannot rename " + partial + " to it: " + ec.message());
  rep.bytes = fs::file_size(out, ec);
  if (opt.kalibr_files) {
    const fs::path p(out);
    const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    rep.camchain_file = (dir / ("camchain-imucam-" + p.stem().string() + ".yaml")).string();
    rep.imu_file = (dir / ("imu-" + p.stem().string() + ".yaml")).string();
    write_kalibr_camchain(rep.camchain_file, d.cam, d.td_prior_s, opt.cam_topic);
    write_kalibr_imu(rep.imu_file, d.imu_calib, opt.imu_topic);
  }
  return rep;
}

} // namespace ovton::core
