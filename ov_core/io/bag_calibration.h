#pragma once
// Where a bag's calibration comes from. A bag carries no calibration of its own; users have it as Kalibr output
// (camchain-imucam-<bag>.yaml and imu-<bag>.yaml beside the bag) or, for EuRoC, as the ASL folder downloaded with it.
#include "ov_core/cam/camera_calib.h"
#include "ov_core/io/dataset.h"
#include "ov_core/types/sensor_data.h"

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace ovton::core {

struct BagCalibration {
  CameraCalib cam;                   ///< the camera of the chosen image topic (select_topic_camera)
  std::vector<KalibrCamera> rig;     ///< every camera of the calibration, cam0 first, with its topic
  bool topics_by_convention = false; ///< an EuRoC folder: camN's topic is the ASL bags' /camN/image_raw
  size_t selected = 0;               ///< which camera of `rig` is `cam` (select_topic_camera)
  ImuCalib imu;
  double td_prior_s = 0.0;                    ///< the chosen camera's Kalibr timeshift_cam_imu (0 for EuRoC)
  std::vector<StateSample> groundtruth;       ///< from a companion folder, when it has one
  std::vector<TdSample> td_truth;             ///< from a companion folder (`ovton simulate` output)
  std::string cam_topic_hint, imu_topic_hint; ///< Kalibr's rostopic entries ("" when absent)
  std::string source;                         ///< what was read, for `ovton info`
};

/// `calib` lists what the user gave (--calib): Kalibr camchain / imu YAML files (told apart by their keys) or folders
/// (an EuRoC folder: cam0/imu0 sensor.yaml, ground truth, td_truth; or a folder with one camchain-imucam*.yaml and one
/// imu*.yaml, and optionally groundtruth/data.csv and td_truth/data.csv as in the SCube layout). Empty: beside the bag
/// B.bag, the folder B/, then camchain-imucam-B.yaml + imu-B.yaml (Kalibr's names), then camchain-imucam.yaml +
/// imu.yaml. Throws DataError naming the bag and every place looked at when nothing is found.
BagCalibration resolve_bag_calibration(const std::string &bag, const std::vector<std::string> &calib);
/// The same, but nothing when `calib` is empty and nothing is found beside the recording (which may then carry its own:
/// a ROS 2 recording's CameraInfo).
std::optional<BagCalibration> find_bag_calibration(const std::string &bag, const std::vector<std::string> &calib);
/// Makes `cam` and `td_prior_s` those of the calibration's camera recorded on `topic` (Kalibr's rostopic; an EuRoC
/// folder's camN is /camN/image_raw) and returns its name for the run's notes. Throws DataError naming the calibration
/// when its cameras (two or more) name topics (Kalibr) and none is `topic`; otherwise cam0, said in the name.
std::string select_topic_camera(BagCalibration &c, const std::string &topic);
/// The calibration's cameras other than the selected one whose topics `types` (topic -> message type) holds as one of
/// `image_types`: a stereo recording's further cameras, in the chain's order (indices into c.rig).
std::vector<size_t> further_cameras(const BagCalibration &c, const std::map<std::string, std::string> &types,
                                    const std::vector<std::string> &image_types);
/// Where find_bag_calibration looks beside `bag`, for messages.
std::string bag_calibration_places(const std::string &bag);
/// The Kalibr file pairs (camchain, imu) looked for beside `bag`, in order.
std::vector<std::pair<std::string, std::string>> bag_calibration_file_pairs(const std::string &bag);

} // namespace ovton::core
