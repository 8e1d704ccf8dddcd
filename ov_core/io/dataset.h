#pragma once
// A replayable dataset folder (EuRoC ASL or SCube), loaded and validated in one place.
#include "ov_core/cam/camera_calib.h"
#include "ov_core/io/imu_gaps.h"
#include "ov_core/types/sensor_data.h"
#include <optional>
#include <string>
#include <vector>

namespace ovton::core {

/// A camera of a rig beyond cam0 (cam1, cam2, ...): its calibration and its own image list, camera clock. An image
/// pairs with the cam0 image of the same stamp.
struct CameraStream {
  CameraCalib cam;
  std::vector<ImageEntry> images;
  /// Its own true offset (mav0/td_truth_camK/data.csv: a simulated camera on a clock of its own): its image stamped
  /// t_cam shows t_imu = t_cam + this. Empty: the rig's td_truth holds for it too.
  std::vector<TdSample> td_truth;
};

struct Dataset {
  std::string root;               ///< folder the user named
  std::string kind;               ///< "euroc", "scube", "rosbag", "mcap" or "ros2bag"
  std::string notes;              ///< what the reader chose on its own (a bag's topics, calibration), for `info`
  std::vector<ImageEntry> images; ///< cam0, time-ordered, camera clock
  std::vector<ImuData> imu;       ///< time-ordered, IMU clock
  CameraCalib cam;
  /// cam1, cam2, ... in the recording's order; empty for a monocular recording (and for a feature-level one).
  std::vector<CameraStream> more_cameras;
  ImuCalib imu_calib;
  std::vector<StateSample> groundtruth; ///< empty when absent; may be position-only (SCube RTK)
  std::vector<TdSample> td_truth;       ///< empty when absent
  double td_prior_s = 0.0;              ///< offset from calibration (Kalibr timeshift_cam_imu), 0 for EuRoC
  /// Set when the recording ends in a cut (a recorder that crashed): the file and what is wrong there. The images and
  /// readings before the cut are listed; a player calls check_not_truncated after the last of them, so that a run
  /// writes its rows up to the cut and then reports it.
  std::string truncated_file, truncated_reason;
  /// IMU gaps within the images' span that the filter propagates through (imu_gaps.h), for the run's output.
  ImuGaps imu_gaps;
  /// What the reader could read but a user should check (an IMU rate other than the calibration's), for the run's
  /// output.
  std::vector<std::string> warnings;

  size_t num_cameras() const { return 1 + more_cameras.size(); }
  bool has_groundtruth() const { return !groundtruth.empty(); }
  bool has_td_truth() const { return !td_truth.empty(); }
  /// True offset at a camera stamp, linearly interpolated (clamped at the ends). Throws when there is no truth.
  double td_truth_at(int64_t t_cam_ns) const;
};

/// Throws DataError(d.truncated_file, d.truncated_reason) when `d` ends in a cut (Dataset::truncated_file).
void check_not_truncated(const Dataset &d);

/// A true offset at a camera stamp from a non-empty td_truth list: linear between samples, clamped at the ends.
double interpolate_td(const std::vector<TdSample> &td_truth, int64_t t_cam_ns);

struct LoadOptions {
  bool check_images_exist = true; ///< stat every listed image (cheap; reading them is the front end's job)
};

/// Loads `dir` (either the folder holding mav0/ or mav0/ itself). Detects EuRoC vs SCube by layout.
/// Throws DataError naming the file and line of the first problem found.
Dataset load_dataset(const std::string &dir, const LoadOptions &opt = {});
Dataset load_euroc(const std::string &dir, const LoadOptions &opt = {});
/// The streams of an EuRoC folder without its calibration (cam0/data.csv, imu0/data.csv; no sensor.yaml read): for
/// `ovton calibrate`. cam.rate_hz and imu_calib.rate_hz are the stamps' median rates; the camera's size, intrinsics and
/// extrinsics and the IMU's noise are left at their defaults for the caller to fill. The same checks of the lists as
/// load_euroc (order, overlap, IMU gaps) except the rate check. Throws DataError naming the file.
Dataset load_euroc_streams(const std::string &dir, const LoadOptions &opt = {});
Dataset load_scube(const std::string &dir, const LoadOptions &opt = {});

/// Keeps the cameras listed (indices into cam0, cam1, ... as loaded; the first becomes the primary camera, whose
/// images drive the replay). Throws UsageError for an index the recording lacks, a repeat, or an empty list.
void select_cameras(Dataset &d, const std::vector<int> &cameras);
/// "0,1" -> {0, 1}; throws UsageError for anything but comma-separated non-negative integers.
std::vector<int> parse_camera_list(const std::string &s);

/// An IMU log in EuRoC's imu0/data.csv format (timestamp [ns], gyro xyz, accel xyz), checked as a folder's is
/// (order, range, spacing against rate_hz); also a flat log outside any folder (`ovton simulate --imu-from FILE`).
std::vector<ImuData> read_euroc_imu_csv(const std::string &csv, double rate_hz);

/// EuRoC sensor.yaml readers (also used by the simulator to copy calibration).
CameraCalib load_euroc_camera_yaml(const std::string &file);
ImuCalib load_euroc_imu_yaml(const std::string &file);

/// One camera of a Kalibr camchain (camchain-imucam.yaml): pinhole with radtan, equidistant or no distortion.
struct KalibrCamera {
  CameraCalib cam;
  double timeshift_cam_imu_s = 0.0; ///< Kalibr's timeshift_cam_imu: t_imu = t_cam + shift, our t_d
  std::string rostopic;             ///< the camera's topic when the chain names it ("" otherwise)
};
/// Kalibr IMU noise file (imu.yaml: an imu0 mapping, or its keys at the top level).
struct KalibrImu {
  ImuCalib imu;
  std::string rostopic;
};
/// Kalibr readers. The chain's extrinsics may be Kalibr's T_cam_imu or an OpenVINS-style T_imu_cam.
KalibrCamera load_kalibr_camchain(const std::string &file, const std::string &cam_name = "cam0");
/// Every camera of a chain (cam0, cam1, ... until one is missing). A camera without its own T_cam_imu / T_imu_cam takes
/// its extrinsics from the previous one through Kalibr's T_cn_cnm1 (camera n-1 to camera n).
std::vector<KalibrCamera> load_kalibr_rig(const std::string &file);
KalibrImu load_kalibr_imu(const std::string &file);

} // namespace ovton::core
