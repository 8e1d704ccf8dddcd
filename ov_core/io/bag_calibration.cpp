#include "ov_core/io/bag_calibration.h"
#include "ov_core/io/csv.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/types/errors.h"

#include <yaml-cpp/yaml.h>

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
  std::optional<KalibrCamera> cam;
  std::optional<KalibrImu> imu;
  std::vector<StateSample> groundtruth;
  std::vector<TdSample> td_truth;
  std::vector<std::string> read; ///< files read, for the summary
};

void set_camera(Parts &p, const std::string &file) {
  if (p.cam)
    throw UsageError("two camera calibrations given (" + p.read.front() + " and " + file + ")");
  p.cam = load_kalibr_camchain(file);
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
    const std::string cam = (mav0 / "cam0" / "sensor.yaml").string(), imu = (mav0 / "imu0" / "sensor.yaml").string();
    KalibrCamera c;
    c.cam = load_euroc_camera_yaml(cam);
    KalibrImu i;
    i.imu = load_euroc_imu_yaml(imu);
    p.cam = c;
    p.imu = i;
    p.read = {cam, imu};
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
  c.cam = p.cam->cam;
  c.td_prior_s = p.cam->timeshift_cam_imu_s;
  c.cam_topic_hint = p.cam->rostopic;
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
    if (!p.cam || !p.imu)
      throw UsageError(std::string("--calib gave no ") + (p.cam ? "IMU" : "camera") +
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

BagCalibration resolve_bag_calibration(const std::string &bag, const std::vector<std::string> &calib) {
  if (auto c = find_bag_calibration(bag, calib))
    return std::move(*c);
  throw DataError(bag, "no calibration found: give --calib (Kalibr camchain + imu YAML, or the EuRoC folder); looked "
                       "for " +
                           bag_calibration_places(bag));
}

} // namespace ovton::core
