#include "ov_core/io/dataset.h"
#include "ov_core/io/csv.h"
#include "ov_core/io/imu_gaps.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/io/yaml_file.h"
#include "ov_core/types/errors.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace fs = std::filesystem;

namespace ovton::core {

namespace {

template <typename T> T get(const YAML::Node &n, const std::string &file, const std::string &key) {
  if (!n[key])
    throw DataError(file, "missing key '" + key + "'");
  return yaml_as<T>(n[key], file, key);
}

double get_finite(const YAML::Node &n, const std::string &file, const std::string &key) {
  const double v = get<double>(n, file, key);
  if (!std::isfinite(v))
    throw DataError(file, yaml_line(n[key]), "non-finite value for '" + key + "'");
  return v;
}

/// A value that must lie in [lo, hi]: rates and noise densities outside any real sensor's range are typos or wrong
/// units (a zero noise density makes the filter trust the IMU absolutely; a rate of 1e-300 Hz overflows every period).
double get_in_range(const YAML::Node &n, const std::string &file, const std::string &key, double lo, double hi,
                    const char *why) {
  const double v = get_finite(n, file, key);
  if (!(v >= lo && v <= hi))
    throw DataError(file, yaml_line(n[key]),
                    "'" + key + "' = " + std::to_string(v) + " is outside [" + std::to_string(lo) + ", " +
                        std::to_string(hi) + "]: " + why);
  return v;
}

/// A map-valued entry (Kalibr's cam0:, imu0:), checked so that a scalar there is reported, not subscripted.
YAML::Node get_map(const YAML::Node &n, const std::string &file, const std::string &key) {
  if (!n[key])
    throw DataError(file, "missing '" + key + "'");
  if (!n[key].IsMap())
    throw DataError(file, yaml_line(n[key]), "'" + key + "' must be a mapping");
  return n[key];
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
    throw DataError(file, yaml_line(t), "'" + key + "' rotation block is not a rotation matrix");
  // A last row other than [0 0 0 1] is not a rigid transform: a transposed matrix (translation in the last row) or a
  // projection; taking its top three rows would drop what the file says.
  if ((T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9)
    throw DataError(file, yaml_line(t),
                    "'" + key + "' last row is [" + std::to_string(T(3, 0)) + " " + std::to_string(T(3, 1)) + " " +
                        std::to_string(T(3, 2)) + " " + std::to_string(T(3, 3)) +
                        "], not [0 0 0 1]: a rigid transform's (a transposed matrix?)");
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
  if (c.width <= 0 || c.height <= 0 || c.width > 20000 || c.height > 20000)
    throw DataError(file, "resolution must be positive and at most 20000 px a side");
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

// Beyond these a reading is not a measurement: high-g MEMS accelerometers stop at ~400 g and the fastest gyros at
// ~70 rad/s (4000 deg/s). A value past them (1e308 from a corrupted file) would otherwise reach the filter as NaN.
constexpr double kMaxGyroRadS = 100.0;
constexpr double kMaxAccelMS2 = 5000.0;
// Stamps are ns since some epoch: negative ones cannot be a sensor clock, and one this close to the end of the int64
// clock (year 2223) leaves no room for adding a time offset.
constexpr int64_t kMaxStampNs = 8000000000000000000LL;

/// A row's stamp: an integer in [0, kMaxStampNs], strictly after the previous row's.
int64_t read_stamp(const TextTableReader &r, const std::string &field, bool has_prev, int64_t prev) {
  const int64_t t = r.to_int64(field, "timestamp");
  if (t < 0)
    r.fail("negative timestamp " + field + " (stamps are nanoseconds since an epoch)");
  if (t > kMaxStampNs)
    r.fail("timestamp " + field + " ns lies beyond the year 2200: not a nanosecond stamp");
  if (has_prev && t <= prev)
    r.fail(t == prev ? "duplicate timestamp " + field : "timestamp " + field + " is not after the previous row");
  return t;
}

/// Median spacing of time-ordered stamps [ns] (0 for fewer than two): the rate checks and the rates of a folder
/// without calibration.
int64_t median_spacing_ns(const std::vector<int64_t> &t) {
  if (t.size() < 2)
    return 0;
  std::vector<int64_t> dt(t.size() - 1);
  for (size_t i = 1; i < t.size(); ++i)
    dt[i - 1] = t[i] - t[i - 1];
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  return dt[dt.size() / 2];
}

/// The stated rate must match the stamps: a list stamped in ms or us (or a sensor.yaml with the wrong rate) shows as a
/// median spacing far from 1/rate. Reported at the first row whose spacing is off by the same factor.
void check_spacing(const std::string &file, const std::vector<int64_t> &t, const std::vector<long> &lines,
                   double rate_hz, const char *rate_key) {
  if (t.size() < 3 || !(rate_hz > 0))
    return;
  std::vector<int64_t> dt(t.size() - 1);
  for (size_t i = 1; i < t.size(); ++i)
    dt[i - 1] = t[i] - t[i - 1];
  const double median = static_cast<double>(median_spacing_ns(t));
  const double expected = 1e9 / rate_hz;
  if (median > expected / 3 && median < expected * 3)
    return;
  size_t k = 0;
  while (k + 1 < dt.size() && (static_cast<double>(dt[k]) > expected / 3 && static_cast<double>(dt[k]) < expected * 3))
    ++k;
  char msg[256];
  std::snprintf(msg, sizeof msg,
                "stamps are %.6g ns apart (median), but %s %.6g Hz means %.6g ns: are the stamps in nanoseconds, and "
                "is the rate right?",
                median, rate_key, rate_hz, expected);
  throw DataError(file, lines[k + 1], msg);
}

std::vector<ImageEntry> read_image_list(const std::string &csv, const std::string &image_dir, const LoadOptions &opt,
                                        double rate_hz) {
  TextTableReader r(csv, ',');
  std::vector<ImageEntry> out;
  std::vector<int64_t> stamps;
  std::vector<long> lines;
  std::vector<std::string> f;
  while (r.next(f)) {
    if (f.size() != 2)
      r.fail("expected 2 columns (timestamp [ns], filename), found " + std::to_string(f.size()));
    ImageEntry e;
    e.t_cam_ns = read_stamp(r, f[0], !out.empty(), out.empty() ? 0 : out.back().t_cam_ns);
    if (f[1].empty())
      r.fail("empty image file name");
    e.path = join_path(image_dir, f[1]);
    if (opt.check_images_exist) {
      std::error_code ec;
      if (!fs::is_regular_file(e.path, ec))
        r.fail("listed image does not exist: " + e.path);
    }
    stamps.push_back(e.t_cam_ns);
    lines.push_back(r.line());
    out.push_back(std::move(e));
  }
  if (out.empty())
    throw DataError(csv, "no images listed");
  check_spacing(csv, stamps, lines, rate_hz, "the camera's rate_hz");
  return out;
}

/// The IMU log; `lines` (when given) receives each reading's line in the file, for errors found later.
std::vector<ImuData> read_imu_csv(const std::string &csv, double rate_hz, std::vector<long> *lines_out = nullptr) {
  TextTableReader r(csv, ',');
  std::vector<ImuData> out;
  out.reserve(1 << 16);
  std::vector<int64_t> stamps;
  std::vector<long> lines;
  std::vector<std::string> f;
  while (r.next(f)) {
    if (f.size() != 7)
      r.fail("expected 7 columns (timestamp, gyro xyz, accel xyz), found " + std::to_string(f.size()));
    ImuData d;
    d.t_imu_ns = read_stamp(r, f[0], !out.empty(), out.empty() ? 0 : out.back().t_imu_ns);
    for (int i = 0; i < 3; ++i) {
      d.wm(i) = r.to_double(f[1 + i], "gyro value");
      d.am(i) = r.to_double(f[4 + i], "accel value");
      if (std::abs(d.wm(i)) > kMaxGyroRadS)
        r.fail("gyro value " + f[1 + i] + " rad/s is beyond any real gyroscope's range (" +
               std::to_string(kMaxGyroRadS) + " rad/s)");
      if (std::abs(d.am(i)) > kMaxAccelMS2)
        r.fail("accel value " + f[4 + i] + " m/s^2 is beyond any real accelerometer's range (" +
               std::to_string(kMaxAccelMS2) + " m/s^2)");
    }
    stamps.push_back(d.t_imu_ns);
    lines.push_back(r.line());
    out.push_back(d);
  }
  if (out.size() < 2)
    throw DataError(csv, "fewer than 2 IMU readings");
  check_spacing(csv, stamps, lines, rate_hz, "the IMU's rate");
  if (lines_out)
    *lines_out = std::move(lines);
  return out;
}

/// IMU gaps over the images' span (imu_gaps.h): counted into d.imu_gaps, a long one refused by its line; a rate other
/// than the calibration's (`rate_source`) is a warning.
void check_imu_gaps(Dataset &d, const std::string &imu_csv, const std::vector<long> &lines,
                    const std::string &rate_source) {
  if (d.images.empty() || d.imu.empty())
    return;
  if (std::string w = imu_rate_mismatch(d.imu, d.imu_calib.rate_hz, rate_source); !w.empty())
    d.warnings.push_back(imu_csv + ": " + w);
  const size_t bad = scan_imu_gaps(
      d.imu.size(), [&](size_t i) { return d.imu[i].t_imu_ns; }, d.images.front().t_cam_ns, d.images.back().t_cam_ns,
      d.imu_calib.rate_hz, d.imu_gaps);
  if (bad < d.imu.size())
    throw DataError(imu_csv, lines[bad],
                    "IMU gap of " + std::to_string((d.imu[bad].t_imu_ns - d.imu[bad - 1].t_imu_ns) / 1000000) +
                        " ms before this row, within the images' span (gaps up to " +
                        std::to_string(static_cast<int>(kMaxImuGapS * 1000)) + " ms are propagated through)");
}

/// Images and IMU must share a clock: when no image lies within the IMU log's span (give or take a second, far more
/// than any camera-IMU offset), the replay would skip every image and the run would write nothing.
void check_overlap(const std::vector<ImageEntry> &images, const std::vector<ImuData> &imu, const std::string &cam_csv,
                   const std::string &imu_csv) {
  constexpr int64_t kMarginNs = 1000000000;
  const int64_t lo = imu.front().t_imu_ns - kMarginNs, hi = imu.back().t_imu_ns + kMarginNs;
  for (const auto &im : images)
    if (im.t_cam_ns >= lo && im.t_cam_ns <= hi)
      return;
  throw DataError(cam_csv, "no image stamp lies within the IMU log's span (" + imu_csv + ": " +
                               std::to_string(imu.front().t_imu_ns) + " to " + std::to_string(imu.back().t_imu_ns) +
                               " ns; images " + std::to_string(images.front().t_cam_ns) + " to " +
                               std::to_string(images.back().t_cam_ns) + " ns): are both in nanoseconds of one clock?");
}

/// cam0/features.csv (`timestamp_ns,feature_id,u,v`, grouped by stamp) attached to the listed images.
void read_features_csv(const std::string &csv, const CameraCalib &cam, std::vector<ImageEntry> &images) {
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
    const Eigen::Vector2d uv(r.to_double(f[2], "u"), r.to_double(f[3], "v"));
    // Undistorting a point far outside the image diverges (NaN in the filter); a tracker never reports one.
    if (std::abs(uv.x() - 0.5 * cam.width) > cam.width || std::abs(uv.y() - 0.5 * cam.height) > cam.height)
      r.fail("feature at (" + f[2] + ", " + f[3] + ") px lies far outside the " + std::to_string(cam.width) + "x" +
             std::to_string(cam.height) + " image");
    per_image[k].push_back({static_cast<size_t>(id), uv});
  }
  for (size_t i = 0; i < images.size(); ++i)
    images[i].features = std::make_shared<const std::vector<PointObservation>>(std::move(per_image[i]));
}

std::string optional_file(const std::string &path) {
  std::error_code ec;
  return fs::exists(path, ec) ? path : std::string();
}

/// A further camera's list: images it lists but lacks are left out rather than refused (a cut of a recording keeps
/// the primary camera's frames; a further camera's missing image only makes that instant monocular).
std::vector<ImageEntry> read_further_camera(const std::string &csv, const std::string &image_dir,
                                            const LoadOptions &opt, double rate_hz) {
  LoadOptions unchecked = opt;
  unchecked.check_images_exist = false;
  std::vector<ImageEntry> images = read_image_list(csv, image_dir, unchecked, rate_hz);
  if (opt.check_images_exist)
    images.erase(
        std::remove_if(images.begin(), images.end(), [](const ImageEntry &e) { return optional_file(e.path).empty(); }),
        images.end());
  return images;
}

/// Rate and noise densities of an IMU, from EuRoC's imu0/sensor.yaml (rate_hz) or Kalibr's imu.yaml (update_rate).
ImuCalib read_imu_calib(const YAML::Node &n, const std::string &file, const std::string &rate_key) {
  ImuCalib c;
  c.rate_hz = get_in_range(n, file, rate_key, 1.0, 1e5, "an IMU's rate in Hz");
  // The filter weighs the IMU by these: zero or negative would make it trust the IMU absolutely (or not be a
  // covariance); values past 1 are not a real sensor's noise in these units.
  const char *density = "a noise density must be positive (units per sqrt(Hz))";
  const char *walk = "a bias random walk must be >= 0 (units per sqrt(Hz))";
  c.gyro_noise_density = get_in_range(n, file, "gyroscope_noise_density", 1e-12, 1.0, density);
  c.gyro_random_walk = get_in_range(n, file, "gyroscope_random_walk", 0.0, 1.0, walk);
  c.accel_noise_density = get_in_range(n, file, "accelerometer_noise_density", 1e-12, 10.0, density);
  c.accel_random_walk = get_in_range(n, file, "accelerometer_random_walk", 0.0, 10.0, walk);
  return c;
}

/// The camera entries EuRoC's cam0/sensor.yaml and Kalibr's camchain cam0 share (their key names differ).
void read_camera_common(const YAML::Node &n, const std::string &file, const char *dist_key, CameraCalib &c) {
  const std::string model = n["camera_model"] ? get<std::string>(n, file, "camera_model") : "pinhole";
  if (model != "pinhole")
    throw DataError(file, yaml_line(n["camera_model"]), "unsupported camera_model '" + model + "' (only pinhole)");
  const auto res = get<std::vector<int>>(n, file, "resolution");
  if (res.size() != 2)
    throw DataError(file, yaml_line(n["resolution"]), "'resolution' must be [width, height]");
  c.width = res[0];
  c.height = res[1];
  c.rate_hz = n["rate_hz"] ? get_in_range(n, file, "rate_hz", 0.1, 1e4, "a camera's rate in Hz") : 20.0;
  c.intrinsics = get_vec<4>(n, file, "intrinsics");
  c.distortion = parse_distortion(get<std::string>(n, file, "distortion_model"), file);
  c.dist_coeffs = get_vec<4>(n, file, dist_key);
}

} // namespace

CameraCalib load_euroc_camera_yaml(const std::string &file) {
  const YAML::Node n = load_yaml_file(file);
  CameraCalib c;
  read_camera_common(n, file, "distortion_coefficients", c);
  c.T_BC = get_transform(n, file, "T_BS");
  check_camera(c, file);
  return c;
}

ImuCalib load_euroc_imu_yaml(const std::string &file) {
  const YAML::Node n = load_yaml_file(file);
  ImuCalib c = read_imu_calib(n, file, "rate_hz");
  if (n["T_BS"])
    c.T_BI = get_transform(n, file, "T_BS");
  return c;
}

namespace {

/// One camera of a loaded chain. `previous`: the T_BC of camera n-1, for a camera that gives only T_cn_cnm1.
KalibrCamera read_kalibr_camera(const YAML::Node &chain, const std::string &chain_file, const std::string &cam_name,
                                const Eigen::Matrix4d *previous) {
  const YAML::Node c0 = get_map(chain, chain_file, cam_name);
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
  else if (previous && c0["T_cn_cnm1"]) // p_cn = T_cn_cnm1 p_cnm1, so T_B_cn = T_B_cnm1 T_cn_cnm1^-1
    c.T_BC = *previous * get_transform(c0, chain_file, "T_cn_cnm1").inverse();
  else
    throw DataError(chain_file, "missing key 'T_cam_imu' (or 'T_imu_cam') in '" + cam_name + "'");
  check_camera(c, chain_file);
  if (c0["timeshift_cam_imu"])
    k.timeshift_cam_imu_s =
        get_in_range(c0, chain_file, "timeshift_cam_imu", -10.0, 10.0, "a camera-IMU time shift in s");
  if (c0["rostopic"])
    k.rostopic = get<std::string>(c0, chain_file, "rostopic");
  return k;
}

} // namespace

KalibrCamera load_kalibr_camchain(const std::string &chain_file, const std::string &cam_name) {
  return read_kalibr_camera(load_yaml_file(chain_file), chain_file, cam_name, nullptr);
}

std::vector<KalibrCamera> load_kalibr_rig(const std::string &chain_file) {
  const YAML::Node chain = load_yaml_file(chain_file);
  std::vector<KalibrCamera> rig;
  rig.push_back(read_kalibr_camera(chain, chain_file, "cam0", nullptr));
  for (int k = 1; chain["cam" + std::to_string(k)]; ++k)
    rig.push_back(read_kalibr_camera(chain, chain_file, "cam" + std::to_string(k), &rig.back().cam.T_BC));
  return rig;
}

KalibrImu load_kalibr_imu(const std::string &imu_file) {
  const YAML::Node imu = load_yaml_file(imu_file);
  const YAML::Node i0 = imu["imu0"] ? get_map(imu, imu_file, "imu0") : imu;
  KalibrImu k;
  // The same plausibility checks as an EuRoC sensor.yaml (noise densities > 0, a rate a real IMU has).
  k.imu = read_imu_calib(i0, imu_file, "update_rate");
  if (i0["rostopic"])
    k.rostopic = get<std::string>(i0, imu_file, "rostopic");
  return k;
}

double Dataset::td_truth_at(int64_t t_cam_ns) const {
  if (td_truth.empty())
    throw UsageError("dataset " + root + " has no td_truth/data.csv");
  return interpolate_td(td_truth, t_cam_ns);
}

void check_not_truncated(const Dataset &d) {
  if (!d.truncated_file.empty())
    throw DataError(d.truncated_file, d.truncated_reason);
}

double interpolate_td(const std::vector<TdSample> &td_truth, int64_t t_cam_ns) {
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

std::vector<ImuData> read_euroc_imu_csv(const std::string &csv, double rate_hz) {
  return read_imu_csv(csv, rate_hz);
}

Dataset load_euroc(const std::string &dir, const LoadOptions &opt) {
  const std::string mav0 = resolve_mav0(dir);
  Dataset d;
  d.root = dir;
  d.kind = "euroc";
  // A recording that never had a calibration (a phone's): say how to get one rather than only what is missing.
  if (optional_file(join_path(mav0, "cam0/sensor.yaml")).empty() &&
      !optional_file(join_path(mav0, "cam0/data.csv")).empty())
    throw DataError(join_path(mav0, "cam0/sensor.yaml"),
                    "file not found: a recording without calibration? `ovton calibrate --dataset " + dir +
                        " --out DIR` estimates one from its images and gyro");
  d.cam = load_euroc_camera_yaml(join_path(mav0, "cam0/sensor.yaml"));
  d.imu_calib = load_euroc_imu_yaml(join_path(mav0, "imu0/sensor.yaml"));
  // Feature-level folders (ovton simulate --features-only) list stamps whose images were never rendered.
  const std::string features = optional_file(join_path(mav0, "cam0/features.csv"));
  LoadOptions list_opt = opt;
  if (!features.empty())
    list_opt.check_images_exist = false;
  const std::string cam_csv = join_path(mav0, "cam0/data.csv"), imu_csv = join_path(mav0, "imu0/data.csv");
  d.images = read_image_list(cam_csv, join_path(mav0, "cam0/data"), list_opt, d.cam.rate_hz);
  if (!features.empty())
    read_features_csv(features, d.cam, d.images);
  else
    for (int k = 1;; ++k) { // cam1, cam2, ... while the folder has them
      const std::string cam = join_path(mav0, "cam" + std::to_string(k));
      if (optional_file(join_path(cam, "sensor.yaml")).empty() || optional_file(join_path(cam, "data.csv")).empty())
        break;
      CameraStream c;
      c.cam = load_euroc_camera_yaml(join_path(cam, "sensor.yaml"));
      c.images = read_further_camera(join_path(cam, "data.csv"), join_path(cam, "data"), list_opt, c.cam.rate_hz);
      if (auto td = optional_file(join_path(mav0, "td_truth_cam" + std::to_string(k) + "/data.csv")); !td.empty())
        c.td_truth = read_td_truth(td);
      d.more_cameras.push_back(std::move(c));
    }
  std::vector<long> imu_lines;
  d.imu = read_imu_csv(imu_csv, d.imu_calib.rate_hz, &imu_lines);
  check_overlap(d.images, d.imu, cam_csv, imu_csv);
  check_imu_gaps(d, imu_csv, imu_lines, join_path(mav0, "imu0/sensor.yaml") + "'s rate_hz");
  if (auto gt = optional_file(join_path(mav0, "state_groundtruth_estimate0/data.csv")); !gt.empty())
    d.groundtruth = read_trajectory(gt);
  if (auto td = optional_file(join_path(mav0, "td_truth/data.csv")); !td.empty())
    d.td_truth = read_td_truth(td);
  return d;
}

Dataset load_euroc_streams(const std::string &dir, const LoadOptions &opt) {
  const std::string mav0 = resolve_mav0(dir);
  Dataset d;
  d.root = dir;
  d.kind = "euroc";
  const std::string cam_csv = join_path(mav0, "cam0/data.csv"), imu_csv = join_path(mav0, "imu0/data.csv");
  // No stated rate to check the stamps against: the lists' own median spacing stands for it (rate 0 skips the
  // check), so that arrival-time stamps with jitter are read as they are.
  d.images = read_image_list(cam_csv, join_path(mav0, "cam0/data"), opt, 0.0);
  std::vector<long> imu_lines;
  d.imu = read_imu_csv(imu_csv, 0.0, &imu_lines);
  std::vector<int64_t> t(d.images.size());
  for (size_t i = 0; i < t.size(); ++i)
    t[i] = d.images[i].t_cam_ns;
  d.cam.rate_hz = 1.0 / std::max(ns_to_s(median_spacing_ns(t)), 1e-6);
  t.resize(d.imu.size());
  for (size_t i = 0; i < t.size(); ++i)
    t[i] = d.imu[i].t_imu_ns;
  d.imu_calib.rate_hz = 1.0 / std::max(ns_to_s(median_spacing_ns(t)), 1e-6);
  check_overlap(d.images, d.imu, cam_csv, imu_csv);
  check_imu_gaps(d, imu_csv, imu_lines, "the stamps' median spacing");
  d.notes = "no calibration read: rates from the stamps' median spacing";
  return d;
}

Dataset load_scube(const std::string &dir, const LoadOptions &opt) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw DataError(dir, "dataset folder not found");
  Dataset d;
  d.root = dir;
  d.kind = "scube";

  const std::vector<KalibrCamera> rig = load_kalibr_rig(join_path(dir, "camchain-imucam.yaml"));
  const KalibrCamera &kc = rig.front();
  d.cam = kc.cam;
  d.td_prior_s = kc.timeshift_cam_imu_s;
  d.imu_calib = load_kalibr_imu(join_path(dir, "imu.yaml")).imu;

  const std::string cam_csv = join_path(dir, "cam0/data.csv"), imu_csv = join_path(dir, "imu0/data.csv");
  d.images = read_image_list(cam_csv, join_path(dir, "cam0/data"), opt, d.cam.rate_hz);
  for (size_t k = 1; k < rig.size(); ++k) { // the chain's further cameras that have images here
    const std::string cam = join_path(dir, "cam" + std::to_string(k));
    if (optional_file(join_path(cam, "data.csv")).empty())
      break;
    d.more_cameras.push_back(
        {rig[k].cam, read_further_camera(join_path(cam, "data.csv"), join_path(cam, "data"), opt, rig[k].cam.rate_hz)});
  }
  std::vector<long> imu_lines;
  d.imu = read_imu_csv(imu_csv, d.imu_calib.rate_hz, &imu_lines);
  check_overlap(d.images, d.imu, cam_csv, imu_csv);
  check_imu_gaps(d, imu_csv, imu_lines, join_path(dir, "imu.yaml") + "'s update_rate");
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

} // namespace ovton::core
