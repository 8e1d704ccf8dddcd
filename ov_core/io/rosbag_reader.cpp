#include "ov_core/io/rosbag_reader.h"
#include "ov_core/io/bag_calibration.h"
#include "ov_core/io/image_store.h"
#include "ov_core/io/recording_topics.h"
#include "ov_core/io/rosbag_messages.h"
#include "ov_core/types/errors.h"

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>

#include <fstream>
#include <map>
#include <memory>
#include <mutex>

namespace ovton::core {

namespace {

const char *const kImageType = "sensor_msgs/Image";
const char *const kCompressedType = "sensor_msgs/CompressedImage";
const char *const kImuType = "sensor_msgs/Imu";

/// Every rosbag/roscpp failure (ros::Exception: bag I/O and format errors, stream overruns of a truncated message)
/// becomes a DataError naming the bag and the message.
template <typename F> auto with_bag_errors(const std::string &file, const std::string &where, F &&f) -> decltype(f()) {
  try {
    return f();
  } catch (const ros::Exception &e) {
    throw DataError(file, where + (where.empty() ? "" : ": ") + "unreadable (" + e.what() +
                              "): the bag is corrupt or truncated");
  }
}

int64_t stamp_ns(const ros::Time &t) {
  return static_cast<int64_t>(t.sec) * 1000000000LL + static_cast<int64_t>(t.nsec);
}

/// A message as its type, or a DataError naming it.
template <typename Msg>
boost::shared_ptr<Msg> instantiate(const rosbag::MessageInstance &m, const std::string &file,
                                   const std::string &where) {
  auto msg = with_bag_errors(file, where, [&] { return m.instantiate<Msg>(); });
  if (!msg)
    throw DataError(file, where + ": not a " + ros::message_traits::DataType<Msg>::value());
  return msg;
}

/// The header stamp of a camera message, after checking it against the calibration's size (for a compressed image by
/// its file header).
template <typename Msg>
int64_t checked_image_stamp(const rosbag::MessageInstance &m, const CameraCalib &cam, const std::string &file,
                            const std::string &where) {
  const auto img = instantiate<Msg>(m, file, where);
  check_image_message(*img, cam.width, cam.height, file, where);
  return stamp_ns(img->header.stamp);
}

/// The images of one topic, read from the bag when the replay asks for them. rosbag::Bag reads through one file handle
/// and one chunk buffer, so reads are serialised.
class BagImageStore : public ImageStore {
public:
  BagImageStore(std::string file, std::string topic, bool compressed, std::unique_ptr<rosbag::Bag> bag)
      : file_(std::move(file)), topic_(std::move(topic)), compressed_(compressed), bag_(std::move(bag)) {}

  rosbag::Bag &bag() const { return *bag_; }
  /// Images by store index: the message and its position in the bag's time order (for errors).
  std::vector<std::pair<rosbag::MessageInstance, size_t>> messages;

  cv::Mat load(const ImageEntry &e) const override {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto &[m, index] = messages.at(e.store_index);
    const std::string where = message_label(index, topic_);
    return compressed_ ? image_to_gray(*instantiate<sensor_msgs::CompressedImage>(m, file_, where), file_, where)
                       : image_to_gray(*instantiate<sensor_msgs::Image>(m, file_, where), file_, where);
  }

private:
  std::string file_, topic_;
  bool compressed_;
  std::unique_ptr<rosbag::Bag> bag_; ///< the MessageInstances point into it: never moved
  mutable std::mutex mutex_;
};

} // namespace

bool rosbag_supported() {
  return true;
}

Dataset load_bag(const std::string &file, const BagOptions &opt) {
  if (!is_rosbag_file(file)) {
    std::ifstream in(file, std::ios::binary);
    throw DataError(file, in ? "not a ROS 1 bag (no #ROSBAG V2.0 header)" : "bag not found or unreadable");
  }
  BagCalibration calib = resolve_bag_calibration(file, opt.calib);
  auto bag = std::make_unique<rosbag::Bag>();
  with_bag_errors(file, "", [&] { bag->open(file, rosbag::bagmode::Read); });

  // Topics and their types come from the bag's index: no message is read for this.
  std::map<std::string, std::string> types;
  {
    rosbag::View all(*bag);
    for (const rosbag::ConnectionInfo *c : all.getConnections())
      types[c->topic] = c->datatype;
  }
  const std::string cam_topic = choose_topic(file, types, opt.cam_topic, calib.cam_topic_hint,
                                             {kImageType, kCompressedType}, "/cam0/image_raw", "--cam-topic");
  const std::string imu_topic =
      choose_topic(file, types, opt.imu_topic, calib.imu_topic_hint, {kImuType}, "/imu0", "--imu-topic");
  const bool compressed = types.at(cam_topic) == kCompressedType;
  auto store = std::make_shared<BagImageStore>(file, cam_topic, compressed, std::move(bag));

  // One pass in the bag's time order over the index of every message (for the message numbers users see in
  // `rosbag info`-style tools); only the two topics' messages are read. Images are read for their header and size and
  // dropped: the pixels are read again when the replay asks.
  RecordingMessages msgs;
  with_bag_errors(file, "", [&] {
    rosbag::View all(store->bag());
    size_t index = 0;
    for (auto it = all.begin(); it != all.end(); ++it, ++index) {
      const rosbag::MessageInstance &m = *it;
      const std::string &topic = m.getTopic();
      if (topic != cam_topic && topic != imu_topic)
        continue;
      const std::string where = message_label(index, topic);
      if (topic == imu_topic) {
        msgs.imu.emplace_back(imu_from_message(*instantiate<sensor_msgs::Imu>(m, file, where), file, where), index);
        continue;
      }
      ImageEntry e;
      e.t_cam_ns = compressed ? checked_image_stamp<sensor_msgs::CompressedImage>(m, calib.cam, file, where)
                              : checked_image_stamp<sensor_msgs::Image>(m, calib.cam, file, where);
      e.path = file + ": " + where;
      e.store_index = store->messages.size();
      store->messages.emplace_back(m, index);
      msgs.images.emplace_back(std::move(e), index);
    }
  });

  Dataset d;
  d.root = file;
  d.kind = "rosbag";
  d.cam = calib.cam;
  d.imu_calib = calib.imu;
  d.td_prior_s = calib.td_prior_s;
  d.groundtruth = std::move(calib.groundtruth);
  d.td_truth = std::move(calib.td_truth);
  finish_recording(file, cam_topic, imu_topic, calib.imu.rate_hz, std::move(msgs), store, d);
  d.notes = "topics " + cam_topic + " (" + std::to_string(d.images.size()) + (compressed ? " compressed" : "") +
            " images), " + imu_topic + " (" + std::to_string(d.imu.size()) + " readings); calibration from " +
            calib.source;
  return d;
}

} // namespace ovton::core
