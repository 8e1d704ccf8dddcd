#include "ov_core/io/ros2_recording.h"
#include "ov_core/io/bag_calibration.h"
#include "ov_core/io/image_message.h"
#include "ov_core/io/image_store.h"
#include "ov_core/io/recording_topics.h"
#include "ov_core/io/ros2_messages.h"
#include "ov_core/types/errors.h"

#include <algorithm>
#include <cstdint>
#include <exception>
#include <map>
#include <optional>
#include <queue>
#include <set>

namespace ovton::core {

namespace {

/// An image message needs its header, size and encoding at load: the first bytes of the message hold them (a long
/// frame_id aside); a compressed image also needs its file header, which a JPEG may put after its EXIF data.
constexpr size_t kRawImagePrefix = 4096;

/// IMU noise when the recording is the only calibration there is: the ADIS16448 values Kalibr's and OpenVINS' EuRoC
/// examples use. The run's config overrides them (imu.gyroscope_noise_density etc.); Dataset::notes says so.
ImuCalib default_imu_noise() {
  ImuCalib c;
  c.gyro_noise_density = 1.6968e-04;
  c.gyro_random_walk = 1.9393e-05;
  c.accel_noise_density = 2.0e-3;
  c.accel_random_walk = 3.0e-3;
  return c;
}

std::string canonical_type(const std::string &type) {
  switch (ros2_type(type)) {
  case Ros2Type::Image:
    return "sensor_msgs/msg/Image";
  case Ros2Type::CompressedImage:
    return "sensor_msgs/msg/CompressedImage";
  case Ros2Type::Imu:
    return "sensor_msgs/msg/Imu";
  case Ros2Type::CameraInfo:
    return "sensor_msgs/msg/CameraInfo";
  case Ros2Type::TfMessage:
    return "tf2_msgs/msg/TFMessage";
  default:
    return type;
  }
}

/// What the walk keeps of one topic.
struct Topic {
  std::string type, encoding;
  Ros2Type kind = Ros2Type::Other;
  size_t messages = 0;
  std::string frame_id;     ///< the first message's header frame_id
  std::exception_ptr error; ///< the first message that could not be read: reported if the topic is chosen
  // images: entry (stamp, path, store index), message number, place, label and size (from the message's header)
  RecordingMessages msgs;
  std::vector<MessagePlace> places;
  std::vector<std::string> labels;
  std::vector<std::pair<uint32_t, uint32_t>> sizes;
  std::optional<Ros2CameraInfo> info;
  std::string info_where;
};

/// The camera's images, read from the recording's files when the replay reaches them.
class Ros2ImageStore : public ImageStore {
public:
  Ros2ImageStore(std::vector<std::shared_ptr<RecordingFile>> files, bool compressed, std::vector<MessagePlace> places,
                 std::vector<std::string> labels)
      : files_(std::move(files)), compressed_(compressed), places_(std::move(places)), labels_(std::move(labels)) {}

  cv::Mat load(const ImageEntry &e) const override {
    const MessagePlace &p = places_.at(e.store_index);
    const RecordingFile &f = *files_.at(p.file);
    const std::string &where = labels_.at(e.store_index);
    const std::vector<uint8_t> bytes = f.fetch(p);
    if (compressed_) {
      const Ros2CompressedImage m = decode_ros2_compressed_image(bytes.data(), bytes.size(), f.path(), where);
      return compressed_to_gray(m.format, m.data.data, m.data.size, f.path(), where);
    }
    return raw_image_to_gray(decode_ros2_image(bytes.data(), bytes.size(), f.path(), where).pixels, f.path(), where);
  }

private:
  std::vector<std::shared_ptr<RecordingFile>> files_;
  bool compressed_;
  std::vector<MessagePlace> places_;
  std::vector<std::string> labels_;
};

/// The IMU -> camera transform from /tf_static: the path between the two frames through the tree, either direction.
std::optional<Eigen::Matrix4d> static_transform(const std::vector<Ros2Transform> &tf, const std::string &from,
                                                const std::string &to) {
  if (from == to)
    return Eigen::Matrix4d::Identity();
  std::map<std::string, std::vector<std::pair<std::string, Eigen::Matrix4d>>> edges; // T_frame_next
  for (const Ros2Transform &t : tf) {
    edges[t.parent].emplace_back(t.child, t.T_parent_child);
    Eigen::Matrix4d inv = Eigen::Matrix4d::Identity();
    inv.topLeftCorner<3, 3>() = t.T_parent_child.topLeftCorner<3, 3>().transpose();
    inv.topRightCorner<3, 1>() = -inv.topLeftCorner<3, 3>() * t.T_parent_child.topRightCorner<3, 1>();
    edges[t.child].emplace_back(t.parent, inv);
  }
  std::map<std::string, Eigen::Matrix4d> T_from; // T_from_frame for every frame reached
  std::queue<std::string> todo;
  T_from[from] = Eigen::Matrix4d::Identity();
  todo.push(from);
  while (!todo.empty()) {
    const std::string f = todo.front();
    todo.pop();
    for (const auto &[next, T] : edges[f]) {
      if (T_from.count(next))
        continue;
      T_from[next] = T_from[f] * T;
      if (next == to)
        return T_from[next];
      todo.push(next);
    }
  }
  return std::nullopt;
}

double median_rate_hz(const std::vector<int64_t> &stamps) {
  std::vector<int64_t> dt;
  for (size_t i = 1; i < stamps.size(); ++i)
    dt.push_back(stamps[i] - stamps[i - 1]);
  if (dt.empty())
    return 0.0;
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
  const int64_t mid = dt[dt.size() / 2];
  return mid > 0 ? 1e9 / static_cast<double>(mid) : 0.0;
}

template <typename T> std::vector<int64_t> sorted_stamps(const std::vector<std::pair<T, size_t>> &v, int64_t T::*m) {
  std::vector<int64_t> s;
  s.reserve(v.size());
  for (const auto &[x, i] : v)
    s.push_back(x.*m);
  std::sort(s.begin(), s.end());
  return s;
}

/// The calibration a recording carries: CameraInfo on the camera's namespace (or the only CameraInfo topic) for the
/// intrinsics, /tf_static for the camera-IMU extrinsics, the IMU's rate from its stamps and default noise.
BagCalibration calibration_from_recording(const std::string &root, const std::map<std::string, Topic> &topics,
                                          const std::string &cam_topic, const std::string &imu_topic,
                                          const std::vector<Ros2Transform> &tf) {
  std::string base = cam_topic;
  if (base.size() > 11 && base.compare(base.size() - 11, 11, "/compressed") == 0)
    base.resize(base.size() - 11);
  const std::string sibling = base.substr(0, base.rfind('/') + 1) + "camera_info";
  const Topic *info = nullptr;
  std::string info_topic;
  std::vector<std::string> candidates;
  for (const auto &[name, t] : topics)
    if (t.kind == Ros2Type::CameraInfo && (t.info || t.error))
      candidates.push_back(name);
  if (topics.count(sibling) && topics.at(sibling).kind == Ros2Type::CameraInfo)
    info_topic = sibling;
  else if (candidates.size() == 1)
    info_topic = candidates.front();
  if (!info_topic.empty())
    info = &topics.at(info_topic);
  if (!info || (!info->info && !info->error))
    throw DataError(root, "no calibration found: give --calib (Kalibr camchain + imu YAML, or the EuRoC folder); "
                          "looked for " +
                              bag_calibration_places(root) + ", and for a sensor_msgs/msg/CameraInfo topic (" +
                              sibling + (candidates.empty() ? "" : " or the only one") + ") in the recording");
  if (info->error)
    std::rethrow_exception(info->error);
  const Topic &cam = topics.at(cam_topic), &imu = topics.at(imu_topic);
  const auto T_BC = static_transform(tf, imu.frame_id, cam.frame_id);
  if (!T_BC)
    throw DataError(root, "the camera's intrinsics are in " + info_topic +
                              " (CameraInfo), but no /tf_static transform links the IMU frame '" + imu.frame_id +
                              "' to the camera frame '" + cam.frame_id +
                              "': give the camera-IMU calibration with --calib (Kalibr camchain + imu YAML)");
  BagCalibration c;
  c.cam = camera_from_info(*info->info, *T_BC, root, info->info_where);
  c.cam.rate_hz = median_rate_hz(sorted_stamps(cam.msgs.images, &ImageEntry::t_cam_ns));
  c.imu = default_imu_noise();
  c.imu.rate_hz = median_rate_hz(sorted_stamps(imu.msgs.imu, &ImuData::t_imu_ns));
  if (!(c.imu.rate_hz > 0))
    throw DataError(root, imu_topic + ": the IMU's rate cannot be told from its stamps");
  c.source = info_topic + " (CameraInfo: intrinsics)" +
             (imu.frame_id == cam.frame_id ? "" : ", /tf_static (" + imu.frame_id + " -> " + cam.frame_id + ")") +
             "; IMU noise: not in the recording, ovton's defaults (set imu.* in the config for your IMU)";
  return c;
}

} // namespace

Dataset build_ros2_dataset(const std::string &root, const std::string &kind,
                           std::vector<std::shared_ptr<RecordingFile>> files, const BagOptions &opt,
                           const std::string &extra_notes) {
  std::optional<BagCalibration> calib = find_bag_calibration(root, opt.calib);
  std::map<std::string, Topic> topics;
  std::vector<Ros2Transform> tf_static;
  std::exception_ptr tf_error;
  size_t index = 0;
  std::string cut_file, cut_reason;

  const auto on_topic = [&](const std::string &name, const std::string &type, const std::string &encoding) {
    Topic &t = topics[name];
    if (t.type.empty()) {
      t.type = canonical_type(type);
      t.encoding = encoding;
      t.kind = encoding == "cdr" ? ros2_type(type) : Ros2Type::Other;
    }
  };
  const auto prefix = [&](const std::string &name) -> size_t {
    const Topic &t = topics.at(name);
    if (t.error || (t.kind == Ros2Type::CameraInfo && t.info))
      return 0;
    if (t.kind == Ros2Type::Image)
      return kRawImagePrefix;
    if (t.kind == Ros2Type::TfMessage)
      return name == "/tf_static" ? SIZE_MAX : 0;
    return t.kind == Ros2Type::Other ? 0 : SIZE_MAX;
  };
  for (uint32_t fi = 0; fi < files.size(); ++fi) {
    RecordingFile &f = *files[fi];
    f.scan(fi, on_topic, prefix, [&](const ScannedMessage &m) {
      Topic &t = topics.at(*m.topic);
      const size_t n = index++;
      ++t.messages;
      const std::string where = message_label(n, *m.topic) + m.location;
      try {
        if (t.kind == Ros2Type::Image || t.kind == Ros2Type::CompressedImage) {
          ImageEntry e;
          uint32_t w = 0, h = 0;
          if (t.kind == Ros2Type::Image) {
            const Ros2Image img = decode_ros2_image(m.data, m.size, f.path(), where, m.full_size);
            check_raw_image(img.pixels, static_cast<int>(img.pixels.width), static_cast<int>(img.pixels.height),
                            f.path(), where);
            e.t_cam_ns = img.header.stamp_ns;
            w = img.pixels.width;
            h = img.pixels.height;
            if (t.frame_id.empty())
              t.frame_id = img.header.frame_id;
          } else {
            const Ros2CompressedImage img = decode_ros2_compressed_image(m.data, m.size, f.path(), where);
            const auto size = compressed_image_size(img.data.data, img.data.size);
            compressed_format(img.format, img.data.data, img.data.size, f.path(), where);
            if (!size)
              throw DataError(f.path(), where + ": the CompressedImage's " + img.format + " header is unreadable (" +
                                            std::to_string(img.data.size) + " bytes)");
            e.t_cam_ns = img.header.stamp_ns;
            w = static_cast<uint32_t>(size->width);
            h = static_cast<uint32_t>(size->height);
            if (t.frame_id.empty())
              t.frame_id = img.header.frame_id;
          }
          e.path = f.path() + ": " + where;
          e.store_index = t.places.size();
          t.places.push_back(m.place);
          t.labels.push_back(where);
          t.sizes.emplace_back(w, h);
          t.msgs.images.emplace_back(std::move(e), n);
        } else if (t.kind == Ros2Type::Imu) {
          std::string frame;
          t.msgs.imu.emplace_back(decode_ros2_imu(m.data, m.size, f.path(), where, &frame), n);
          if (t.msgs.imu.size() == 1)
            t.frame_id = frame;
        } else if (t.kind == Ros2Type::CameraInfo) {
          t.info = decode_ros2_camera_info(m.data, m.size, f.path(), where);
          t.info_where = where;
        } else if (t.kind == Ros2Type::TfMessage) {
          const auto tf = decode_ros2_tf(m.data, m.size, f.path(), where);
          tf_static.insert(tf_static.end(), tf.begin(), tf.end());
        }
      } catch (const DataError &) {
        // Reported only if the topic is the one read: a recording may hold topics ovton does not need in forms it
        // cannot read (a depth image, a custom encoding).
        if (t.kind == Ros2Type::TfMessage)
          tf_error = std::current_exception();
        else
          t.error = std::current_exception();
      }
    });
    if (cut_file.empty() && !f.cut().empty()) {
      cut_file = f.path();
      cut_reason = f.cut();
    }
  }

  std::map<std::string, std::string> types;
  for (const auto &[name, t] : topics)
    types[name] = t.type;
  const std::string cam_hint = calib ? calib->cam_topic_hint : "", imu_hint = calib ? calib->imu_topic_hint : "";
  const std::string cam_topic =
      choose_topic(root, types, opt.cam_topic, cam_hint, {"sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage"},
                   "/cam0/image_raw", "--cam-topic");
  const std::string imu_topic =
      choose_topic(root, types, opt.imu_topic, imu_hint, {"sensor_msgs/msg/Imu"}, "/imu0", "--imu-topic");
  for (const std::string &name : {cam_topic, imu_topic}) {
    const Topic &t = topics.at(name);
    if (t.encoding != "cdr")
      throw DataError(root, "topic " + name + " is recorded in the message encoding '" + t.encoding +
                                "': ovton reads ROS 2 messages in CDR");
    if (t.error)
      std::rethrow_exception(t.error);
  }
  Topic &cam = topics.at(cam_topic);
  Topic &imu = topics.at(imu_topic);
  if (cam.messages == 0 || imu.messages == 0)
    throw DataError(root, "topic " + (cam.messages == 0 ? cam_topic : imu_topic) + " has no messages");
  std::string camera;
  if (calib) {
    camera = select_topic_camera(*calib, cam_topic);
  } else {
    if (tf_error)
      std::rethrow_exception(tf_error);
    calib = calibration_from_recording(root, topics, cam_topic, imu_topic, tf_static);
  }
  // Every image's size against its camera's calibration (from the message headers: no pixel is decoded here).
  const auto check_sizes = [&](const Topic &t, const CameraCalib &c) {
    for (size_t i = 0; i < t.sizes.size(); ++i)
      if (static_cast<int>(t.sizes[i].first) != c.width || static_cast<int>(t.sizes[i].second) != c.height)
        throw DataError(files.at(t.places[i].file)->path(),
                        t.labels[i] + ": image is " + std::to_string(t.sizes[i].first) + "x" +
                            std::to_string(t.sizes[i].second) + " px, the camera calibration says " +
                            std::to_string(c.width) + "x" + std::to_string(c.height));
  };
  check_sizes(cam, calib->cam);
  // The rig's further cameras whose topics the recording holds (a stereo recording's cam1), each with its own store.
  std::vector<size_t> further;
  if (!camera.empty())
    further = further_cameras(*calib, types, {"sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage"});
  std::vector<CameraStream> more;
  std::string further_notes;
  for (size_t k : further) {
    const std::string &name = calib->rig[k].rostopic;
    Topic &t = topics.at(name);
    if (t.error)
      std::rethrow_exception(t.error);
    if (t.msgs.images.empty() || t.encoding != "cdr")
      continue;
    check_sizes(t, calib->rig[k].cam);
    auto s = std::make_shared<Ros2ImageStore>(files, t.kind == Ros2Type::CompressedImage, std::move(t.places),
                                              std::move(t.labels));
    more.push_back({calib->rig[k].cam, finish_camera_images(root, name, std::move(t.msgs.images), s)});
    further_notes +=
        ", " + name + " (cam" + std::to_string(k) + ", " + std::to_string(more.back().images.size()) + " images)";
  }

  Dataset d;
  d.root = root;
  d.kind = kind;
  d.cam = calib->cam;
  d.imu_calib = calib->imu;
  d.td_prior_s = calib->td_prior_s;
  d.groundtruth = std::move(calib->groundtruth);
  d.td_truth = std::move(calib->td_truth);
  const bool compressed = cam.kind == Ros2Type::CompressedImage;
  auto store = std::make_shared<Ros2ImageStore>(files, compressed, std::move(cam.places), std::move(cam.labels));
  RecordingMessages m;
  m.images = std::move(cam.msgs.images);
  m.imu = std::move(imu.msgs.imu);
  finish_recording(root, cam_topic, imu_topic, d.imu_calib.rate_hz, std::move(m), store, d);
  d.more_cameras = std::move(more);
  d.notes = "topics " + cam_topic + " (" + std::to_string(d.images.size()) + (compressed ? " compressed" : "") +
            " images)" + further_notes + ", " + imu_topic + " (" + std::to_string(d.imu.size()) +
            " readings), by header stamp; calibration from " + calib->source +
            (camera.empty() ? "" : ", its " + camera) + extra_notes;
  if (!cut_file.empty()) {
    d.truncated_file = cut_file;
    d.truncated_reason = cut_reason + ": the recording was cut short (a recorder that stopped without closing "
                                      "the file?); the messages before it were replayed";
    d.notes += "; TRUNCATED: " + cut_file + ": " + cut_reason;
  }
  return d;
}

} // namespace ovton::core
