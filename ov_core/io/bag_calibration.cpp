#include "ov_core/io/bag_calibration.h"
#include "ov_core/io/csv.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/types/errors.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <optional>

namespace fs = std::filesystem;

namespace ovton::core {

namespace {

bool is_file(const fs::path &p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

bool is_dir(const fs::path &p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

/// What one piece of calibration contributed; a complete calibration needs a camera and an IMU.
struct Parts {
  std::vector<KalibrCamera> rig; ///< the calibration's cameras, cam0 first (empty: none given yet)
  bool topics_by_convention = false;
  std::optional<KalibrImu> imu;
  std::vector<StateSample> groundtruth;
  std::vector<TdSample> td_truth;
  std::vector<std::string> read; ///< files read, for the summary
};

void set_camera(Parts &p, const std::string &file) {
  if (!p.rig.empty())
    throw UsageError("two camera calibrations given (" + p.read.front() + " and " + file + ")");
  p.rig = load_kalibr_rig(file);
  p.read.push_back(file);
}

void set_imu(Parts &p, const std::string &file) {
  if (p.imu)
    throw UsageError("two IMU calibrations given (the second is " + file + ")");
  p.imu = load_kalibr_imu(file);
  p.read.push_back(file);
}

/// A Kalibr YAML file, told apart by its keys: a camchain has cam0, an IMU file imu0 (or update_rate at the top).
void add_yaml(Parts &p, const std::string &file) {
  YAML::Node n;
  try {
    n = YAML::LoadFile(file);
  } catch (const YAML::Exception &e) {
    throw DataError(file, e.mark.line + 1, "unreadable YAML: " + e.msg);
  }
  if (n.IsMap() && n["cam0"])
    set_camera(p, file);
  else if (n.IsMap() && (n["imu0"] || n["update_rate"]))
    set_imu(p, file);
  else
    throw DataError(file, "neither a Kalibr camchain (cam0:) nor a Kalibr IMU file (imu0:)");
}

void add_optional_truth(Parts &p, const fs::path &gt, const fs::path &td) {
  if (is_file(gt)) {
    p.groundtruth = read_trajectory(gt.string());
    p.read.push_back(gt.string());
  }
  if (is_file(td)) {
    p.td_truth = read_td_truth(td.string());
    p.read.push_back(td.string());
  }
}

/// The single file in `dir` whose name starts with `prefix` and ends in .yaml ("" when none).
std::string only_match(const fs::path &dir, const std::string &prefix) {
  std::string found;
  for (const auto &e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (!e.is_regular_file() || name.rfind(prefix, 0) != 0 || e.path().extension() != ".yaml")
      continue;
    if (!found.empty())
      throw DataError(dir.string(), "several " + prefix + "*.yaml files: name the one to use with --calib");
    found = e.path().string();
  }
  return found;
}

/// A folder: EuRoC (mav0/ or cam0/sensor.yaml inside) or Kalibr files (SCube layout). False when it is neither.
bool add_folder(Parts &p, const fs::path &dir) {
  const fs::path mav0 = is_dir(dir / "mav0") ? dir / "mav0" : dir;
  if (is_file(mav0 / "cam0" / "sensor.yaml")) {
    const std::string imu = (mav0 / "imu0" / "sensor.yaml").string();
    p.read.clear();
    // camN/sensor.yaml names no topic; the ASL bags that come with these folders record camera N as /camN/image_raw.
    for (int k = 0; is_file(mav0 / ("cam" + std::to_string(k)) / "sensor.yaml"); ++k) {
      const std::string cam = (mav0 / ("cam" + std::to_string(k)) / "sensor.yaml").string();
      KalibrCamera c;
      c.cam = load_euroc_camera_yaml(cam);
      c.rostopic = "/cam" + std::to_string(k) + "/image_raw";
      p.rig.push_back(c);
      p.read.push_back(cam);
    }
    p.topics_by_convention = true;
    KalibrImu i;
    i.imu = load_euroc_imu_yaml(imu);
    p.imu = i;
    p.read.push_back(imu);
    add_optional_truth(p, mav0 / "state_groundtruth_estimate0" / "data.csv", mav0 / "td_truth" / "data.csv");
    return true;
  }
  const std::string chain = only_match(dir, "camchain-imucam"), imu = only_match(dir, "imu");
  if (chain.empty() || imu.empty())
    return false;
  set_camera(p, chain);
  set_imu(p, imu);
  add_optional_truth(p, dir / "groundtruth" / "data.csv", dir / "td_truth" / "data.csv");
  return true;
}

BagCalibration finish(Parts &&p) {
  BagCalibration c;
  c.rig = std::move(p.rig);
  c.topics_by_convention = p.topics_by_convention;
  c.cam = c.rig.front().cam;
  c.td_prior_s = c.rig.front().timeshift_cam_imu_s;
  c.cam_topic_hint = c.rig.front().rostopic;
  c.imu = p.imu->imu;
  c.imu_topic_hint = p.imu->rostopic;
  c.groundtruth = std::move(p.groundtruth);
  c.td_truth = std::move(p.td_truth);
  for (size_t i = 0; i < p.read.size(); ++i)
    c.source += (i ? ", " : "") + p.read[i];
  return c;
}

} // namespace

std::optional<BagCalibration> find_bag_calibration(const std::string &bag, const std::vector<std::string> &calib) {
  Parts p;
  if (!calib.empty()) {
    for (const auto &c : calib) {
      if (is_dir(c)) {
        if (!add_folder(p, c))
          throw DataError(c, "not a calibration folder: no mav0/cam0/sensor.yaml, and not one camchain-imucam*.yaml "
                             "with one imu*.yaml");
      } else {
        require_file(c);
        add_yaml(p, c);
      }
    }
    if (p.rig.empty() || !p.imu)
      throw UsageError(std::string("--calib gave no ") + (p.rig.empty() ? "camera" : "IMU") +
                       " calibration: give a Kalibr camchain and imu YAML, or an EuRoC folder");
    return finish(std::move(p));
  }
  const fs::path b(bag), dir = b.parent_path().empty() ? fs::path(".") : b.parent_path();
  const std::string stem = b.stem().string();
  const fs::path companion = dir / stem;
  if (is_dir(companion) && add_folder(p, companion))
    return finish(std::move(p));
  for (const auto &[chain, imu] : bag_calibration_file_pairs(bag)) {
    if (is_file(chain) && is_file(imu)) {
      set_camera(p, chain);
      set_imu(p, imu);
      return finish(std::move(p));
    }
  }
  return std::nullopt;
}

std::vector<std::pair<std::string, std::string>> bag_calibration_file_pairs(const std::string &bag) {
  const fs::path b(bag), dir = b.parent_path().empty() ? fs::path(".") : b.parent_path();
  const std::string stem = b.stem().string();
  return {{(dir / ("camchain-imucam-" + stem + ".yaml")).string(), (dir / ("imu-" + stem + ".yaml")).string()},
          {(dir / "camchain-imucam.yaml").string(), (dir / "imu.yaml").string()}};
}

std::string bag_calibration_places(const std::string &bag) {
  const fs::path b(bag), dir = b.parent_path().empty() ? fs::path(".") : b.parent_path();
  const std::string stem = b.stem().string();
  return (dir / stem).string() + "/, " + (dir / ("camchain-imucam-" + stem + ".yaml")).string() + " + imu-" + stem +
         ".yaml, and camchain-imucam.yaml + imu.yaml there";
}

std::string select_topic_camera(BagCalibration &c, const std::string &topic) {
  std::string named;
  for (size_t k = 0; k < c.rig.size(); ++k) {
    if (c.rig[k].rostopic.empty())
      continue;
    if (c.rig[k].rostopic == topic) {
      c.selected = k;
      c.cam = c.rig[k].cam;
      c.td_prior_s = c.rig[k].timeshift_cam_imu_s;
      return "cam" + std::to_string(k);
    }
    named += std::string(named.empty() ? "" : ", ") + "cam" + std::to_string(k) + " " + c.rig[k].rostopic;
  }
  if (c.topics_by_convention)
    return "cam0 (its folder names no topics)";
  if (c.rig.size() == 1 && !named.empty()) // one camera calibrated: recorded under another name, most likely
    return "cam0 (calibrated on " + c.rig[0].rostopic + ")";
  // A camera's intrinsics and lever arm on another camera's images would run without complaint and be wrong.
  if (!named.empty())
    throw DataError(c.source, "the image topic " + topic + " is none of the calibration's cameras (" + named +
                                  "): choose one of those topics with --cam-topic, or give the calibration of " +
                                  topic + " with --calib");
  return "cam0 (the calibration names no topics)";
}

std::vector<size_t> further_cameras(const BagCalibration &c, const std::map<std::string, std::string> &types,
                                    const std::vector<std::string> &image_types) {
  std::vector<size_t> out;
  for (size_t k = 0; k < c.rig.size(); ++k) {
    const auto it = types.find(c.rig[k].rostopic);
    if (k != c.selected && it != types.end() &&
        std::find(image_types.begin(), image_types.end(), it->second) != image_types.end())
      out.push_back(k);
  }
  return out;
}

BagCalibration resolve_bag_calibration(const std::string &bag, const std::vector<std::string> &calib) {
  if (auto c = find_bag_calibration(bag, calib))
    return std::move(*c);
  throw DataError(bag, "no calibration found: give --calib (Kalibr camchain + imu YAML, or the EuRoC folder); looked "
                       "for " +
                           bag_calibration_places(bag));
}

} // namespace ovton::core
