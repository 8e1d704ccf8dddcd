#include "ov_core/io/rosbag_reader.h"
#include "ov_core/io/bag_calibration.h"
#include "ov_core/io/image_store.h"
#include "ov_core/io/rosbag_messages.h"
#include "ov_core/types/errors.h"

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <set>

namespace ovton::core {

namespace {

const char *const kImageType = "sensor_msgs/Image";
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

std::string message_label(size_t index, const std::string &topic) {
  return "message " + std::to_string(index) + " (" + topic + ")";
}

/// The images of one topic, read from the bag when the replay asks for them. rosbag::Bag reads through one file handle
/// and one chunk buffer, so reads are serialised.
class BagImageStore : public ImageStore {
public:
  BagImageStore(std::string file, std::string topic, std::unique_ptr<rosbag::Bag> bag)
      : file_(std::move(file)), topic_(std::move(topic)), bag_(std::move(bag)) {}

  /// Images by store index: the message and its position in the bag's time order (for errors).
  std::vector<std::pair<rosbag::MessageInstance, size_t>> messages;

  cv::Mat load(const ImageEntry &e) const override {
    std::lock_guard<std::mutex> lock(mutex_);
    // Not a structured binding: C++17 lambdas cannot capture one (clang refuses it).
    const rosbag::MessageInstance &m = messages.at(e.store_index).first;
    const std::string where = message_label(messages.at(e.store_index).second, topic_);
    const auto img = with_bag_errors(file_, where, [&] { return m.instantiate<sensor_msgs::Image>(); });
    if (!img)
      throw DataError(file_, where + ": not a sensor_msgs/Image");
    return image_to_gray(*img, file_, where);
  }

private:
  std::string file_, topic_;
  std::unique_ptr<rosbag::Bag> bag_; ///< the MessageInstances point into it: never moved
  mutable std::mutex mutex_;
};

/// The topic to read: the one asked for, else the calibration's, else the only one of that type, else the usual name.
std::string choose_topic(const std::string &file, const std::map<std::string, std::string> &types,
                         const std::string &asked, const std::string &hint, const char *type, const char *usual,
                         const char *flag) {
  std::string listing;
  for (const auto &[t, ty] : types)
    listing += (listing.empty() ? "" : ", ") + t + " [" + ty + "]";
  if (!asked.empty()) {
    const auto it = types.find(asked);
    if (it == types.end())
      throw DataError(file, "no topic " + asked + " in the bag (topics: " + listing + ")");
    if (it->second != type)
      throw DataError(file, "topic " + asked + " holds " + it->second + ", not " + type);
    return asked;
  }
  std::vector<std::string> of_type;
  for (const auto &[t, ty] : types)
    if (ty == type)
      of_type.push_back(t);
  if (of_type.empty())
    throw DataError(file, std::string("no ") + type + " topic in the bag (topics: " + listing + ")");
  for (const std::string &pref : {hint, std::string(usual)})
    if (!pref.empty() && std::find(of_type.begin(), of_type.end(), pref) != of_type.end())
      return pref;
  if (of_type.size() == 1)
    return of_type.front();
  throw DataError(file, std::string("several ") + type + " topics (" + listing + "): choose one with " + flag);
}

int64_t stamp_ns(const ros::Time &t) {
  return static_cast<int64_t>(t.sec) * 1000000000LL + static_cast<int64_t>(t.nsec);
}

/// Sorts by stamp (a bag is in receive order, which can differ from the sensor's) and rejects duplicate stamps.
template <typename T, typename Stamp>
void sort_and_check(std::vector<std::pair<T, size_t>> &v, Stamp stamp, const std::string &file,
                    const std::string &topic) {
  std::stable_sort(v.begin(), v.end(), [&](const auto &a, const auto &b) { return stamp(a.first) < stamp(b.first); });
  for (size_t i = 1; i < v.size(); ++i)
    if (stamp(v[i].first) == stamp(v[i - 1].first))
      throw DataError(file, message_label(v[i].second, topic) + ": duplicate header stamp " +
                                std::to_string(stamp(v[i].first)) + " ns (also " +
                                message_label(v[i - 1].second, topic) + ")");
}

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
  const std::string cam_topic =
      choose_topic(file, types, opt.cam_topic, calib.cam_topic_hint, kImageType, "/cam0/image_raw", "--cam-topic");
  const std::string imu_topic =
      choose_topic(file, types, opt.imu_topic, calib.imu_topic_hint, kImuType, "/imu0", "--imu-topic");

  // One pass in the bag's time order over the index of every message (for the message numbers users see in
  // `rosbag info`-style tools); only the two topics' messages are read. Images are read for their header and size and
  // dropped: the pixels are read again when the replay asks.
  std::vector<std::pair<ImuData, size_t>> imu;
  std::vector<std::pair<ImageEntry, size_t>> images;
  std::vector<rosbag::MessageInstance> image_msgs;
  with_bag_errors(file, "", [&] {
    rosbag::View all(*bag);
    size_t index = 0;
    for (auto it = all.begin(); it != all.end(); ++it, ++index) {
      const rosbag::MessageInstance &m = *it;
      const std::string &topic = m.getTopic();
      if (topic != cam_topic && topic != imu_topic)
        continue;
      const std::string where = message_label(index, topic);
      if (topic == imu_topic) {
        const auto u = with_bag_errors(file, where, [&] { return m.instantiate<sensor_msgs::Imu>(); });
        if (!u)
          throw DataError(file, where + ": not a sensor_msgs/Imu");
        imu.emplace_back(imu_from_message(*u, file, where), index);
      } else {
        const auto img = with_bag_errors(file, where, [&] { return m.instantiate<sensor_msgs::Image>(); });
        if (!img)
          throw DataError(file, where + ": not a sensor_msgs/Image");
        check_image_message(*img, calib.cam.width, calib.cam.height, file, where);
        ImageEntry e;
        e.t_cam_ns = stamp_ns(img->header.stamp);
        e.path = file + ": " + where;
        e.store_index = image_msgs.size();
        image_msgs.push_back(m);
        images.emplace_back(std::move(e), index);
      }
    }
  });
  if (images.empty())
    throw DataError(file, "no message on " + cam_topic);
  if (imu.size() < 2)
    throw DataError(file, "fewer than 2 messages on " + imu_topic);
  sort_and_check(
      images, [](const ImageEntry &e) { return e.t_cam_ns; }, file, cam_topic);
  sort_and_check(
      imu, [](const ImuData &d) { return d.t_imu_ns; }, file, imu_topic);
  const int64_t max_gap_ns = static_cast<int64_t>(10.0 / calib.imu.rate_hz * 1e9);
  for (size_t i = 1; i < imu.size(); ++i)
    if (imu[i].first.t_imu_ns - imu[i - 1].first.t_imu_ns > max_gap_ns)
      throw DataError(file, message_label(imu[i].second, imu_topic) + ": IMU gap of " +
                                std::to_string((imu[i].first.t_imu_ns - imu[i - 1].first.t_imu_ns) * 1e-6) +
                                " ms before it (rate " + std::to_string(calib.imu.rate_hz) + " Hz)");

  Dataset d;
  d.root = file;
  d.kind = "rosbag";
  d.cam = calib.cam;
  d.imu_calib = calib.imu;
  d.td_prior_s = calib.td_prior_s;
  d.groundtruth = std::move(calib.groundtruth);
  d.td_truth = std::move(calib.td_truth);
  d.notes = "topics " + cam_topic + " (" + std::to_string(images.size()) + " images), " + imu_topic + " (" +
            std::to_string(imu.size()) + " readings); calibration from " + calib.source;
  auto store = std::make_shared<BagImageStore>(file, cam_topic, std::move(bag));
  for (auto &[e, index] : images) {
    store->messages.emplace_back(image_msgs[e.store_index], index);
    e.store_index = store->messages.size() - 1;
    e.store = store;
    d.images.push_back(std::move(e));
  }
  d.imu.reserve(imu.size());
  for (const auto &[u, index] : imu)
    d.imu.push_back(u);
  return d;
}

} // namespace ovton::core
