#include "ov_core/io/recording_topics.h"
#include "ov_core/io/imu_gaps.h"
#include "ov_core/types/errors.h"

#include <algorithm>

namespace ovton::core {

namespace {

/// Sorts by stamp (a recording is in receive order, which can differ from the sensor's) and rejects duplicates.
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

std::string message_label(size_t index, const std::string &topic) {
  return "message " + std::to_string(index) + " (" + topic + ")";
}

void check_imu_reading(const ImuData &d, const std::string &file, const std::string &where) {
  if (!d.wm.allFinite() || !d.am.allFinite())
    throw DataError(file, where + ": non-finite angular velocity or linear acceleration");
}

std::string choose_topic(const std::string &file, const std::map<std::string, std::string> &types,
                         const std::string &asked, const std::string &hint, const std::vector<std::string> &accepted,
                         const std::string &usual, const std::string &flag) {
  std::string listing, wanted;
  for (const auto &[t, ty] : types)
    listing += (listing.empty() ? "" : ", ") + t + " [" + ty + "]";
  for (const auto &a : accepted)
    wanted += (wanted.empty() ? "" : " or ") + a;
  const auto is_accepted = [&](const std::string &ty) {
    return std::find(accepted.begin(), accepted.end(), ty) != accepted.end();
  };
  if (!asked.empty()) {
    const auto it = types.find(asked);
    if (it == types.end())
      throw DataError(file, "no topic " + asked + " in the recording (topics: " + listing + ")");
    if (!is_accepted(it->second))
      throw DataError(file, "topic " + asked + " holds " + it->second + ", not " + wanted);
    return asked;
  }
  std::vector<std::string> of_type;
  for (const auto &[t, ty] : types)
    if (is_accepted(ty))
      of_type.push_back(t);
  if (of_type.empty())
    throw DataError(file, "no " + wanted + " topic in the recording (topics: " + listing + ")");
  for (const std::string &pref : {hint, usual})
    if (!pref.empty() && std::find(of_type.begin(), of_type.end(), pref) != of_type.end())
      return pref;
  if (of_type.size() == 1)
    return of_type.front();
  throw DataError(file, "several " + wanted + " topics (" + listing + "): choose one with " + flag);
}

std::vector<ImageEntry> finish_camera_images(const std::string &file, const std::string &topic,
                                             std::vector<std::pair<ImageEntry, size_t>> &&images,
                                             const std::shared_ptr<const ImageStore> &store) {
  sort_and_check(
      images, [](const ImageEntry &e) { return e.t_cam_ns; }, file, topic);
  std::vector<ImageEntry> out;
  out.reserve(images.size());
  for (auto &[e, index] : images) {
    e.store = store;
    out.push_back(std::move(e));
  }
  return out;
}

void finish_recording(const std::string &file, const std::string &cam_topic, const std::string &imu_topic,
                      double imu_rate_hz, RecordingMessages &&m, const std::shared_ptr<const ImageStore> &store,
                      Dataset &d) {
  if (m.images.empty())
    throw DataError(file, "no message on " + cam_topic);
  if (m.imu.size() < 2)
    throw DataError(file, "fewer than 2 messages on " + imu_topic);
  d.images = finish_camera_images(file, cam_topic, std::move(m.images), store);
  sort_and_check(
      m.imu, [](const ImuData &u) { return u.t_imu_ns; }, file, imu_topic);
  const size_t bad = scan_imu_gaps(
      m.imu.size(), [&](size_t i) { return m.imu[i].first.t_imu_ns; }, d.images.front().t_cam_ns,
      d.images.back().t_cam_ns, imu_rate_hz, d.imu_gaps);
  if (bad < m.imu.size())
    throw DataError(file, message_label(m.imu[bad].second, imu_topic) + ": IMU gap of " +
                              std::to_string((m.imu[bad].first.t_imu_ns - m.imu[bad - 1].first.t_imu_ns) / 1000000) +
                              " ms before it, within the images' span (gaps up to " +
                              std::to_string(static_cast<int>(kMaxImuGapS * 1000)) + " ms are propagated through)");
  d.imu.clear();
  d.imu.reserve(m.imu.size());
  for (const auto &[u, index] : m.imu)
    d.imu.push_back(u);
  if (std::string w = imu_rate_mismatch(d.imu, imu_rate_hz, "the IMU calibration's update_rate"); !w.empty())
    d.warnings.push_back(file + ": " + imu_topic + ": " + w);
}

} // namespace ovton::core
