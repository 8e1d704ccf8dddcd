#pragma once
// What every recording reader (ROS 1 bags, MCAP files, ROS 2 bags) does alike once it has listed the topics and read
// the messages' headers: choose the camera and IMU topics, order the messages by header stamp (the sensor's time, not
// the recorder's receive time), refuse duplicate stamps and long IMU gaps (imu_gaps.h), and hand the result over as a
// Dataset whose images stay in the recording (ImageStore) until the replay reaches them.
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_store.h"

#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace ovton::core {

/// "message N (topic)": how errors name a message (N: its position in the recording, from 0).
std::string message_label(size_t index, const std::string &topic);

/// Throws DataError(file, where + ...) for a reading with non-finite angular velocity or linear acceleration.
void check_imu_reading(const ImuData &d, const std::string &file, const std::string &where);

/// The topic to read among `types` (topic -> message type): the one asked for (which must hold one of `accepted`),
/// else the calibration's hint, else `usual`, else the only topic of an accepted type. Throws DataError naming the
/// recording and listing its topics when there is none or several to choose from (`flag` says how to choose).
std::string choose_topic(const std::string &file, const std::map<std::string, std::string> &types,
                         const std::string &asked, const std::string &hint, const std::vector<std::string> &accepted,
                         const std::string &usual, const std::string &flag);

/// Images (t_cam_ns, path, store_index set) and IMU readings as read, each with its message number for errors.
struct RecordingMessages {
  std::vector<std::pair<ImageEntry, size_t>> images;
  std::vector<std::pair<ImuData, size_t>> imu;
};

/// A camera's images as read, sorted by header stamp and pointing at `store`. Throws DataError naming `file` and the
/// messages for a duplicate stamp.
std::vector<ImageEntry> finish_camera_images(const std::string &file, const std::string &topic,
                                             std::vector<std::pair<ImageEntry, size_t>> &&images,
                                             const std::shared_ptr<const ImageStore> &store);

/// Fills d.images (each pointing at `store`) and d.imu from `m`, sorted by header stamp. Throws DataError naming
/// `file` when a topic has no message (the IMU: fewer than 2), for duplicate stamps and for an IMU gap within the
/// images' span longer than kMaxImuGapS (shorter ones are counted in d.imu_gaps).
void finish_recording(const std::string &file, const std::string &cam_topic, const std::string &imu_topic,
                      double imu_rate_hz, RecordingMessages &&m, const std::shared_ptr<const ImageStore> &store,
                      Dataset &d);

} // namespace ovton::core
