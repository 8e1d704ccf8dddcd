#include "ov_core/io/dataset.h"
#include "ov_core/io/csv.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/types/errors.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace ov_core {

namespace {

/// EuRoC sensor.yaml files start with OpenCV's "%YAML:1.0" directive, which yaml-cpp rejects; drop it.
YAML::Node load_yaml(const std::string &file) {
  require_file(file);
  std::ifstream in(file);
  std::stringstream ss;
  std::string line;
  bool first = true;
  while (std::getline(in, line)) {
    if (first && line.rfind("%YAML", 0) == 0)
      line = "";
    first = false;
    ss << line << "\n";
  }
  try {
    YAML::Node n = YAML::Load(ss.str());
    if (!n.IsMap())
      throw DataError(file, "expected a YAML mapping at the top level");
    return n;
  } catch (const YAML::Exception &e) {
    throw DataError(file, e.mark.line + 1, std::string("unreadable YAML: ") + e.msg);
  }
}

template <typename T> T get(const YAML::Node &n, const std::string &file, const std::string &key) {
  if (!n[key])
    throw DataError(file, "missing key '" + key + "'");
  try {
    return n[key].as<T>();
  } catch (const YAML::Exception &e) {
    throw DataError(file, e.mark.line + 1, "bad value for '" + key + "': " + e.msg);
  }
}

double get_finite(const YAML::Node &n, const std::string &file, const std::string &key) {
  const double v = get<double>(n, file, key);
  if (!std::isfinite(v))
    throw DataError(file, "non-finite value for '" + key + "'");
  return v;
}

template <int N>
Eigen::Matrix<double, N, 1> get_vec(const YAML::Node &n, const std::string &file, const std::string &key) {
  const auto v = get<std::vector<double>>(n, file, key);
  if (static_cast<int>(v.size()) != N)
    throw DataError(file, "'" + key + "' must have " + std::to_string(N) + " values, has " + std::to_string(v.size()));
  Eigen::Matrix<double, N, 1> out;
  for (int i = 0; i < N; ++i) {
    if (!std::isfinite(v[i]))
      throw DataError(file, "non-finite value in '" + key + "'");
    out(i) = v[i];
  }
  return out;
}

/// A 4x4 rigid transform, either EuRoC style {rows, cols, data: [16]} or Kalibr style (list of 4 rows).
Eigen::Matrix4d get_transform(const YAML::Node &n, const std::string &file, const std::string &key) {
  if (!n[key])
    throw DataError(file, "missing key '" + key + "'");
  const YAML::Node t = n[key];
  std::vector<double> d;
  try {
    if (t.IsMap()) {
      d = t["data"].as<std::vector<double>>();
    } else if (t.IsSequence()) {
      for (const auto &row : t)
        for (const auto &x : row)
          d.push_back(x.as<double>());
    }
  } catch (const YAML::Exception &e) {
    throw DataError(file, e.mark.line + 1, "bad matrix '" + key + "': " + e.msg);
  }
  if (d.size() != 16)
    throw DataError(file, "'" + key + "' must be a 4x4 matrix (16 values), has " + std::to_string(d.size()));
  Eigen::Matrix4d T;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      if (!std::isfinite(d[4 * r + c]))
        throw DataError(file, "non-finite value in '" + key + "'");
      T(r, c) = d[4 * r + c];
    }
  const Eigen::Matrix3d R = T.block<3, 3>(0, 0);
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-3 || std::abs(R.determinant() - 1.0) > 1e-3)
    throw DataError(file, "'" + key + "' rotation block is not a rotation matrix");
  return T;
}

DistortionModel parse_distortion(const std::string &s, const std::string &file) {
  if (s == "radial-tangential" || s == "radtan" || s == "plumb_bob")
    return DistortionModel::RadTan;
  if (s == "equidistant" || s == "fisheye")
    return DistortionModel::Equidistant;
  if (s == "none") // Kalibr's undistorted pinhole: radtan with zero coefficients
    return DistortionModel::RadTan;
  throw DataError(file, "unknown distortion model '" + s + "' (expected radial-tangential or equidistant)");
}

void check_camera(const CameraCalib &c, const std::string &file) {
  if (c.width <= 0 || c.height <= 0)
    throw DataError(file, "resolution must be positive");
  if (c.intrinsics(0) <= 0 || c.intrinsics(1) <= 0)
    throw DataError(file, "focal lengths must be positive");
}

/// EuRoC folders are named either by their parent (holding mav0/) or mav0/ itself.
std::string resolve_mav0(const std::string &dir) {
  std::error_code ec;
  if (!fs::exists(dir, ec))
    throw DataError(dir, "dataset folder not found");
  if (!fs::is_directory(dir, ec))
    throw DataError(dir, "not a folder");
  if (fs::is_directory(fs::path(dir) / "mav0", ec))
    return (fs::path(dir) / "mav0").string();
  if (fs::is_directory(fs::path(dir) / "cam0", ec))
    return dir;
  throw DataError(dir, "not an EuRoC folder: neither mav0/ nor cam0/ inside");
}

std::vector<ImageEntry> read_image_list(const std::string &csv, const std::string &image_dir, const LoadOptions &opt) {
  TextTableReader r(csv, ',');
  std::vector<ImageEntry> out;
  std::vector<std::string> f;
  while (r.next(f)) {
    if (f.size() != 2)
      r.fail("expected 2 columns (timestamp [ns], filename), found " + std::to_string(f.size()));
    ImageEntry e;
    e.t_cam_ns = r.to_int64(f[0], "timestamp");
    if (f[1].empty())
      r.fail("empty image file name");
    e.path = join_path(image_dir, f[1]);
    if (!out.empty() && e.t_cam_ns <= out.back().t_cam_ns)
      r.fail(e.t_cam_ns == out.back().t_cam_ns ? "duplicate timestamp " + f[0]
                                               : "timestamp " + f[0] + " is not after the previous row");
    if (opt.check_images_exist) {
      std::error_code ec;
      if (!fs::is_regular_file(e.path, ec))
        r.fail("listed image does not exist: " + e.path);
    }
    out.push_back(std::move(e));
  }
  if (out.empty())
    throw DataError(csv, "no images listed");
  return out;
}

std::vector<ImuData> read_imu_csv(const std::string &csv, double rate_hz) {
  TextTableReader r(csv, ',');
  std::vector<ImuData> out;
  out.reserve(1 << 16);
  std::vector<std::string> f;
  // A hole of more than a few nominal periods breaks propagation silently; reject it loudly.
  const int64_t max_gap_ns = rate_hz > 0 ? static_cast<int64_t>(10.0 / rate_hz * 1e9) : 100000000;
  while (r.next(f)) {
    if (f.size() != 7)
      r.fail("expected 7 columns (timestamp, gyro xyz, accel xyz), found " + std::to_string(f.size()));
    ImuData d;
    d.t_imu_ns = r.to_int64(f[0], "timestamp");
    for (int i = 0; i < 3; ++i) {
      d.wm(i) = r.to_double(f[1 + i], "gyro value");
      d.am(i) = r.to_double(f[4 + i], "accel value");
    }
    if (!out.empty()) {
      const int64_t dt = d.t_imu_ns - out.back().t_imu_ns;
      if (dt <= 0)
        r.fail(dt == 0 ? "duplicate timestamp " + f[0] : "timestamp " + f[0] + " is not after the previous row");
      if (dt > max_gap_ns)
        r.fail("IMU gap of " + std::to_string(dt * 1e-6) + " ms before this row (rate " + std::to_string(rate_hz) +
               " Hz)");
    }
    out.push_back(d);
  }
  if (out.size() < 2)
    throw DataError(csv, "fewer than 2 IMU readings");
  return out;
}

/// cam0/features.csv (`timestamp_ns,feature_id,u,v`, grouped by stamp) attached to the listed images.
void read_features_csv(const std::string &csv, std::vector<ImageEntry> &images) {
  TextTableReader r(csv, ',');
  std::vector<std::string> f;
  size_t k = 0;
  std::vector<std::vector<PointObservation>> per_image(images.size());
  while (r.next(f)) {
    if (f.size() != 4)
      r.fail("expected 4 columns (timestamp_ns, feature_id, u, v), found " + std::to_string(f.size()));
    const int64_t t = r.to_int64(f[0], "timestamp");
    while (k < images.size() && images[k].t_cam_ns < t)
      ++k;
    if (k == images.size() || images[k].t_cam_ns != t)
      r.fail("timestamp " + f[0] + " is not an image listed in cam0/data.csv (or rows are out of order)");
    const int64_t id = r.to_int64(f[1], "feature id");
    if (id < 0)
      r.fail("negative feature id");
    per_image[k].push_back({static_cast<size_t>(id), Eigen::Vector2d(r.to_double(f[2], "u"), r.to_double(f[3], "v"))});
  }
  for (size_t i = 0; i < images.size(); ++i)
    images[i].features = std::make_shared<const std::vector<PointObservation>>(std::move(per_image[i]));
}

std::string optional_file(const std::string &path) {
  std::error_code ec;
  return fs::exists(path, ec) ? path : std::string();
}

} // namespace

CameraCalib load_euroc_camera_yaml(const std::string &file) {
  const YAML::Node n = load_yaml(file);
  CameraCalib c;
  const auto res = get<std::vector<int>>(n, file, "resolution");
  if (res.size() != 2)
    throw DataError(file, "'resolution' must be [width, height]");
  c.width = res[0];
  c.height = res[1];
  c.rate_hz = n["rate_hz"] ? get_finite(n, file, "rate_hz") : 20.0;
  const std::string model = n["camera_model"] ? get<std::string>(n, file, "camera_model") : "pinhole";
  if (model != "pinhole")
    throw DataError(file, "unsupported camera_model '" + model + "' (only pinhole)");
  c.intrinsics = get_vec<4>(n, file, "intrinsics");
  c.distortion = parse_distortion(get<std::string>(n, file, "distortion_model"), file);
  c.dist_coeffs = get_vec<4>(n, file, "distortion_coefficients");
  c.T_BC = get_transform(n, file, "T_BS");
  check_camera(c, file);
  return c;
}

ImuCalib load_euroc_imu_yaml(const std::string &file) {
  const YAML::Node n = load_yaml(file);
  ImuCalib c;
  c.rate_hz = get_finite(n, file, "rate_hz");
  c.gyro_noise_density = get_finite(n, file, "gyroscope_noise_density");
  c.gyro_random_walk = get_finite(n, file, "gyroscope_random_walk");
  c.accel_noise_density = get_finite(n, file, "accelerometer_noise_density");
  c.accel_random_walk = get_finite(n, file, "accelerometer_random_walk");
  if (n["T_BS"])
    c.T_BI = get_transform(n, file, "T_BS");
  if (c.rate_hz <= 0)
    throw DataError(file, "rate_hz must be positive");
  return c;
}

KalibrCamera load_kalibr_camchain(const std::string &chain_file, const std::string &cam_name) {
  const YAML::Node chain = load_yaml(chain_file);
  if (!chain[cam_name])
    throw DataError(chain_file, "missing '" + cam_name + "'");
  const YAML::Node c0 = chain[cam_name];
  KalibrCamera k;
  CameraCalib &c = k.cam;
  const std::string model = c0["camera_model"] ? get<std::string>(c0, chain_file, "camera_model") : "pinhole";
  if (model != "pinhole")
    throw DataError(chain_file, "unsupported camera_model '" + model + "' (only pinhole, with radtan or equidistant)");
  c.intrinsics = get_vec<4>(c0, chain_file, "intrinsics");
  c.distortion = parse_distortion(get<std::string>(c0, chain_file, "distortion_model"), chain_file);
  // Kalibr writes no coefficients for distortion_model none.
  if (c0["distortion_coeffs"] || get<std::string>(c0, chain_file, "distortion_model") != "none")
    c.dist_coeffs = get_vec<4>(c0, chain_file, "distortion_coeffs");
  const auto res = get<std::vector<int>>(c0, chain_file, "resolution");
  if (res.size() != 2)
    throw DataError(chain_file, "'resolution' must be [width, height]");
  c.width = res[0];
  c.height = res[1];
  c.rate_hz = c0["rate_hz"] ? get_finite(c0, chain_file, "rate_hz") : 20.0;
  // Kalibr writes T_cam_imu (IMU-frame points into the camera frame), so T_BC is its inverse; OpenVINS-style chains
  // write T_imu_cam = T_BC itself.
  if (c0["T_cam_imu"])
    c.T_BC = get_transform(c0, chain_file, "T_cam_imu").inverse();
  else if (c0["T_imu_cam"])
    c.T_BC = get_transform(c0, chain_file, "T_imu_cam");
  else
    throw DataError(chain_file, "missing key 'T_cam_imu' (or 'T_imu_cam') in '" + cam_name + "'");
  check_camera(c, chain_file);
  if (c0["timeshift_cam_imu"])
    k.timeshift_cam_imu_s = get_finite(c0, chain_file, "timeshift_cam_imu");
  if (c0["rostopic"])
    k.rostopic = get<std::string>(c0, chain_file, "rostopic");
  return k;
}

KalibrImu load_kalibr_imu(const std::string &imu_file) {
  const YAML::Node imu = load_yaml(imu_file);
  const YAML::Node i0 = imu["imu0"] ? imu["imu0"] : imu;
  KalibrImu k;
  ImuCalib &c = k.imu;
  c.rate_hz = get_finite(i0, imu_file, "update_rate");
  c.gyro_noise_density = get_finite(i0, imu_file, "gyroscope_noise_density");
  c.gyro_random_walk = get_finite(i0, imu_file, "gyroscope_random_walk");
  c.accel_noise_density = get_finite(i0, imu_file, "accelerometer_noise_density");
  c.accel_random_walk = get_finite(i0, imu_file, "accelerometer_random_walk");
  if (c.rate_hz <= 0)
    throw DataError(imu_file, "update_rate must be positive");
  if (i0["rostopic"])
    k.rostopic = get<std::string>(i0, imu_file, "rostopic");
  return k;
}

double Dataset::td_truth_at(int64_t t_cam_ns) const {
  if (td_truth.empty())
    throw UsageError("dataset " + root + " has no td_truth/data.csv");
  if (t_cam_ns <= td_truth.front().t_cam_ns)
    return td_truth.front().td_s;
  if (t_cam_ns >= td_truth.back().t_cam_ns)
    return td_truth.back().td_s;
  auto it = std::lower_bound(td_truth.begin(), td_truth.end(), t_cam_ns,
                             [](const TdSample &s, int64_t t) { return s.t_cam_ns < t; });
  const TdSample &b = *it, &a = *(it - 1);
  const double u = static_cast<double>(t_cam_ns - a.t_cam_ns) / static_cast<double>(b.t_cam_ns - a.t_cam_ns);
  return a.td_s + u * (b.td_s - a.td_s);
}

Dataset load_euroc(const std::string &dir, const LoadOptions &opt) {
  const std::string mav0 = resolve_mav0(dir);
  Dataset d;
  d.root = dir;
  d.kind = "euroc";
  d.cam = load_euroc_camera_yaml(join_path(mav0, "cam0/sensor.yaml"));
  d.imu_calib = load_euroc_imu_yaml(join_path(mav0, "imu0/sensor.yaml"));
  // Feature-level folders (ovton simulate --features-only) list stamps whose images were never rendered.
  const std::string features = optional_file(join_path(mav0, "cam0/features.csv"));
  LoadOptions list_opt = opt;
  if (!features.empty())
    list_opt.check_images_exist = false;
  d.images = read_image_list(join_path(mav0, "cam0/data.csv"), join_path(mav0, "cam0/data"), list_opt);
  if (!features.empty())
    read_features_csv(features, d.images);
  d.imu = read_imu_csv(join_path(mav0, "imu0/data.csv"), d.imu_calib.rate_hz);
  if (auto gt = optional_file(join_path(mav0, "state_groundtruth_estimate0/data.csv")); !gt.empty())
    d.groundtruth = read_trajectory(gt);
  if (auto td = optional_file(join_path(mav0, "td_truth/data.csv")); !td.empty())
    d.td_truth = read_td_truth(td);
  return d;
}

Dataset load_scube(const std::string &dir, const LoadOptions &opt) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw DataError(dir, "dataset folder not found");
  Dataset d;
  d.root = dir;
  d.kind = "scube";

  const KalibrCamera kc = load_kalibr_camchain(join_path(dir, "camchain-imucam.yaml"));
  d.cam = kc.cam;
  d.td_prior_s = kc.timeshift_cam_imu_s;
  d.imu_calib = load_kalibr_imu(join_path(dir, "imu.yaml")).imu;

  d.images = read_image_list(join_path(dir, "cam0/data.csv"), join_path(dir, "cam0/data"), opt);
  d.imu = read_imu_csv(join_path(dir, "imu0/data.csv"), d.imu_calib.rate_hz);
  if (auto gt = optional_file(join_path(dir, "groundtruth/data.csv")); !gt.empty())
    d.groundtruth = read_trajectory(gt);
  if (auto td = optional_file(join_path(dir, "td_truth/data.csv")); !td.empty())
    d.td_truth = read_td_truth(td);
  return d;
}

Dataset load_dataset(const std::string &dir, const LoadOptions &opt) {
  std::error_code ec;
  if (fs::is_regular_file(fs::path(dir) / "camchain-imucam.yaml", ec))
    return load_scube(dir, opt);
  return load_euroc(dir, opt);
}

} // namespace ov_core
