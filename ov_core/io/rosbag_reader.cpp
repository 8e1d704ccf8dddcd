#include "ov_core/io/rosbag_reader.h"
#include "ov_core/io/bag_calibration.h"
#include "ov_core/io/image_store.h"
#include "ov_core/io/recording_topics.h"
#include "ov_core/io/ros2_messages.h"
#include "ov_core/io/rosbag_check.h"
#include "ov_core/types/errors.h"

#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <new>

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
  } catch (const std::bad_alloc &) {
    // A length field the structure check cannot see (inside a compressed chunk) asked for more memory than there is.
    throw DataError(file, where + (where.empty() ? "" : ": ") +
                              "unreadable (a length beyond the memory there is): the bag is corrupt");
  }
}

/// A message's serialised bytes, copied out of the bag. They are decoded by ovton's own reader (ros2_messages.h,
/// Wire::Ros1), which checks every length against the message: roscpp's deserialiser sizes a vector by whatever a
/// damaged length field says (4 GiB) before it looks.
std::vector<uint8_t> raw_bytes(const rosbag::MessageInstance &m, const std::string &file, const std::string &where) {
  return with_bag_errors(file, where, [&] {
    std::vector<uint8_t> b(m.size());
    ros::serialization::OStream s(b.data(), static_cast<uint32_t>(b.size()));
    m.write(s);
    return b;
  });
}

/// The gray pixels of a camera message (checked against `check` instead when given: then an empty Mat) and its stamp.
cv::Mat read_image(const rosbag::MessageInstance &m, bool compressed, const std::string &file, const std::string &where,
                   const CameraCalib *check, int64_t *stamp_ns) {
  const std::vector<uint8_t> b = raw_bytes(m, file, where);
  if (compressed) {
    const Ros2CompressedImage img = decode_ros2_compressed_image(b.data(), b.size(), file, where, 0, Wire::Ros1);
    if (stamp_ns)
      *stamp_ns = img.header.stamp_ns;
    if (check) {
      check_compressed_image(img.format, img.data.data, img.data.size, check->width, check->height, file, where);
      return cv::Mat();
    }
    return compressed_to_gray(img.format, img.data.data, img.data.size, file, where);
  }
  const Ros2Image img = decode_ros2_image(b.data(), b.size(), file, where, 0, Wire::Ros1);
  if (stamp_ns)
    *stamp_ns = img.header.stamp_ns;
  if (check) {
    check_raw_image(img.pixels, check->width, check->height, file, where);
    return cv::Mat();
  }
  return raw_image_to_gray(img.pixels, file, where);
}

/// The images of the camera topics (the primary's, then a rig's further cameras'), read from the bag when the replay
/// asks for them. rosbag::Bag reads through one file handle and one chunk buffer, so reads are serialised.
class BagImageStore : public ImageStore {
public:
  BagImageStore(std::string file, std::vector<std::string> topics, std::vector<bool> compressed,
                std::unique_ptr<rosbag::Bag> bag)
      : file_(std::move(file)), topics_(std::move(topics)), compressed_(std::move(compressed)), bag_(std::move(bag)) {}

  rosbag::Bag &bag() const { return *bag_; }
  /// Images by store index: the message, its position in the bag's time order (for errors) and its topic's slot.
  struct Message {
    rosbag::MessageInstance m;
    size_t index, slot;
  };
  std::vector<Message> messages;

  cv::Mat load(const ImageEntry &e) const override {
    std::lock_guard<std::mutex> lock(mutex_);
    const Message &m = messages.at(e.store_index);
    return read_image(m.m, compressed_.at(m.slot), file_, message_label(m.index, topics_.at(m.slot)), nullptr, nullptr);
  }

private:
  std::string file_;
  std::vector<std::string> topics_;
  std::vector<bool> compressed_;
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
  check_rosbag_structure(file);
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
  const std::string camera = select_topic_camera(calib, cam_topic);
  // Slot 0 the primary camera, then the rig's further cameras whose topics the bag holds (a stereo bag's cam1).
  std::vector<std::string> cam_topics = {cam_topic};
  std::vector<CameraCalib> cams = {calib.cam};
  const std::vector<size_t> further = further_cameras(calib, types, {kImageType, kCompressedType});
  for (size_t k : further) {
    cam_topics.push_back(calib.rig[k].rostopic);
    cams.push_back(calib.rig[k].cam);
  }
  std::vector<bool> compressed;
  std::map<std::string, size_t> slot_of;
  for (size_t s = 0; s < cam_topics.size(); ++s) {
    compressed.push_back(types.at(cam_topics[s]) == kCompressedType);
    slot_of[cam_topics[s]] = s;
  }
  auto store = std::make_shared<BagImageStore>(file, cam_topics, compressed, std::move(bag));

  // One pass in the bag's time order over the index of every message (for the message numbers users see in
  // `rosbag info`-style tools); only the two topics' messages are read. Images are read for their header and size and
  // dropped: the pixels are read again when the replay asks.
  RecordingMessages msgs;
  std::vector<std::vector<std::pair<ImageEntry, size_t>>> more(further.size());
  with_bag_errors(file, "", [&] {
    rosbag::View all(store->bag());
    size_t index = 0;
    for (auto it = all.begin(); it != all.end(); ++it, ++index) {
      const rosbag::MessageInstance &m = *it;
      const std::string &topic = m.getTopic();
      const auto slot = slot_of.find(topic);
      if (slot == slot_of.end() && topic != imu_topic)
        continue;
      const std::string where = message_label(index, topic);
      if (topic == imu_topic) {
        const std::vector<uint8_t> b = raw_bytes(m, file, where);
        msgs.imu.emplace_back(decode_ros2_imu(b.data(), b.size(), file, where, nullptr, Wire::Ros1), index);
        continue;
      }
      const size_t s = slot->second;
      ImageEntry e;
      read_image(m, compressed[s], file, where, &cams[s], &e.t_cam_ns);
      e.path = file + ": " + where;
      e.store_index = store->messages.size();
      store->messages.push_back({m, index, s});
      (s == 0 ? msgs.images : more[s - 1]).emplace_back(std::move(e), index);
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
  std::string further_notes;
  for (size_t i = 0; i < further.size(); ++i) {
    if (more[i].empty())
      continue;
    d.more_cameras.push_back({cams[i + 1], finish_camera_images(file, cam_topics[i + 1], std::move(more[i]), store)});
    further_notes += ", " + cam_topics[i + 1] + " (cam" + std::to_string(further[i]) + ", " +
                     std::to_string(d.more_cameras.back().images.size()) + " images)";
  }
  d.notes = "topics " + cam_topic + " (" + std::to_string(d.images.size()) + (compressed[0] ? " compressed" : "") +
            " images)" + further_notes + ", " + imu_topic + " (" + std::to_string(d.imu.size()) +
            " readings); calibration from " + calib.source + ", its " + camera;
  return d;
}

} // namespace ovton::core
