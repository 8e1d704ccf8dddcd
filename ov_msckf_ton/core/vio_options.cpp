#include "ov_msckf_ton/core/vio_options.h"
#include "ov_core/io/yaml_file.h"
#include "ov_core/types/errors.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <functional>
#include <ostream>
#include <set>
#include <vector>

namespace ovton::msckf {

namespace {

/// One entry of the option table: section.key, how to read it from a YAML scalar (with the file named in errors),
/// how to print it. Keys are written once, here; loading and printing both walk this table.
struct Field {
  const char *section;
  const char *key;
  std::function<void(const YAML::Node &, const std::string &)> read;
  std::function<void(std::ostream &)> print;
};

int line_of(const YAML::Node &n) {
  return n.Mark().line + 1;
}

template <typename T> Field field(const char *section, const char *key, T &ref) {
  return {section, key,
          [&ref, key](const YAML::Node &n, const std::string &file) {
            if (!n.IsScalar())
              throw ovton::core::DataError(file, line_of(n), std::string("'") + key + "' must be a single value");
            try {
              ref = n.as<T>();
            } catch (const YAML::Exception &e) {
              throw ovton::core::DataError(file, line_of(n), std::string("bad value for '") + key + "': " + e.msg);
            }
            if constexpr (std::is_floating_point_v<T>)
              if (!std::isfinite(ref))
                throw ovton::core::DataError(file, line_of(n), std::string("non-finite value for '") + key + "'");
          },
          [&ref](std::ostream &os) {
            if constexpr (std::is_same_v<T, bool>)
              os << (ref ? "true" : "false");
            else
              os << ref;
          }};
}

/// One key that sets the same option of several components (e.g. the plateau stop of every network): read into the
/// first, copied to the others; printed from the first.
template <typename T> Field shared_field(const char *section, const char *key, std::vector<T *> refs) {
  Field f = field(section, key, *refs.front());
  const auto read_first = f.read;
  f.read = [read_first, refs](const YAML::Node &n, const std::string &file) {
    read_first(n, file);
    for (T *r : refs)
      *r = *refs.front();
  };
  return f;
}

/// An enum read from its name; `parse` throws ovton::core::UsageError for unknown names.
template <typename E>
Field enum_field(const char *section, const char *key, E &ref, std::function<E(const std::string &)> parse,
                 std::function<std::string(E)> name) {
  return {section, key,
          [&ref, key, parse](const YAML::Node &n, const std::string &file) {
            if (!n.IsScalar())
              throw ovton::core::DataError(file, line_of(n), std::string("'") + key + "' must be a single value");
            try {
              ref = parse(n.as<std::string>());
            } catch (const ovton::core::UsageError &e) {
              throw ovton::core::DataError(file, line_of(n), std::string("'") + key + "': " + e.what());
            }
          },
          [&ref, name](std::ostream &os) { os << name(ref); }};
}

template <typename E> std::function<E(const std::string &)> parser(std::vector<std::pair<const char *, E>> names) {
  return [names](const std::string &s) {
    std::string valid;
    for (const auto &[n, e] : names) {
      if (s == n)
        return e;
      valid += (valid.empty() ? "" : ", ") + std::string(n);
    }
    throw ovton::core::UsageError("unknown value '" + s + "' (expected " + valid + ")");
  };
}

template <typename E> std::function<std::string(E)> namer(std::vector<std::pair<const char *, E>> names) {
  return [names](E e) {
    for (const auto &[n, v] : names)
      if (v == e)
        return std::string(n);
    return std::string("?");
  };
}

const std::vector<std::pair<const char *, SirVelocity>> kSirVelocity = {{"backward", SirVelocity::Backward},
                                                                        {"central", SirVelocity::Central}};
const std::vector<std::pair<const char *, FirstVelocity>> kFirstVelocity = {{"none", FirstVelocity::None},
                                                                            {"next", FirstVelocity::Next}};
const std::vector<std::pair<const char *, ovton::core::ImageEqualization>> kEqualization = {
    {"none", ovton::core::ImageEqualization::None},
    {"histogram", ovton::core::ImageEqualization::Histogram},
    {"clahe", ovton::core::ImageEqualization::Clahe}};

std::vector<Field> fields(VioOptions &o) {
  auto &td = o.td;
  auto &ton = o.ton;
  auto &up = o.update;
  auto &tr = o.track;
  auto &in = o.init;
  const char *T = "time_offset", *N = "ton", *U = "update", *L = "slam", *C = "calibration", *Z = "zupt",
             *K = "tracker", *I = "imu", *S = "init";
  auto &cal = o.calibration;
  auto &its_train = ton.fvon.its.train, &f2f_train = ton.fvon.f2f.train, &tpn_train = ton.tpn.tpn.train;
  return {
      field("rig", "max_cameras", o.rig.max_cameras),
      enum_field<TdMode>(T, "mode", td.mode, parse_td_mode, [](TdMode m) { return to_string(m); }),
      enum_field<TdProcess>(T, "process", td.process, parse_td_process, [](TdProcess p) { return to_string(p); }),
      field(T, "init_s", td.init_s),
      field(T, "sigma_init_s", td.sigma_init_s),
      field(T, "random_walk", td.random_walk),
      field(T, "random_walk_tpn", td.random_walk_tpn),
      field(T, "rate_sigma_init", td.rate_sigma_init),
      field(T, "rate_random_walk", td.rate_random_walk),
      field(T, "rate_max", ton.tpn.td_rate_max),
      field(T, "adaptive_noise", td.adaptive_noise),
      field(T, "adaptive_block_s", td.adaptive_block_s),
      field(T, "model_check", td.model_check),
      field(T, "model_check_window_s", td.model_check_window_s),
      field(T, "model_check_z", td.model_check_z),
      field(T, "model_check_min_step_s", td.model_check_min_step_s),
      field(T, "jacobian_rate_window_s", td.jacobian_rate_window_s),
      enum_field<SirVelocity>(T, "sir_velocity", td.sir_velocity, parser(kSirVelocity), namer(kSirVelocity)),
      enum_field<FirstVelocity>(T, "first_velocity", td.first_velocity, parser(kFirstVelocity), namer(kFirstVelocity)),
      field(T, "velocity_debias", up.msckf.td_velocity_debias),
      field(T, "clone_trend", td.clone_trend),
      field(T, "clone_trend_tau_s", td.clone_trend_tau_s),
      field(T, "per_camera", td.per_camera),
      field(T, "per_camera_sigma_init_s", td.per_camera_sigma_init_s),
      field(T, "per_camera_random_walk", td.per_camera_random_walk),
      field(T, "per_camera_rate", td.per_camera_rate),
      field(T, "search", td.search.enabled),
      field(T, "search_range_s", td.search.range_s),
      field(N, "fvon_max_labels", ton.fvon.max_labels),
      field(N, "fvon_min_f2f_labels", ton.fvon.min_f2f_labels),
      field(N, "fvon_gate_px_s", ton.fvon.gate_px_s),
      field(N, "its_epochs", ton.fvon.its.train.max_epochs),
      field(N, "f2f_epochs", ton.fvon.f2f.train.max_epochs),
      field(N, "tpn_epochs", ton.tpn.tpn.train.max_epochs),
      field(N, "tpn_min_labels", ton.tpn.min_labels),
      field(N, "tpn_start_sigma_s", ton.tpn_start_sigma_s),
      field(N, "tpn_label_images", ton.tpn_label_images),
      field(N, "its_residual", ton.fvon.its.residual),
      field(N, "tpn_residual", ton.tpn.tpn.residual),
      field(N, "f2f_inverse_depth", ton.fvon.f2f.inverse_depth_input),
      shared_field<int>(N, "plateau_epochs",
                        {&its_train.plateau_epochs, &f2f_train.plateau_epochs, &tpn_train.plateau_epochs}),
      shared_field<double>(N, "plateau_rel", {&its_train.plateau_rel, &f2f_train.plateau_rel, &tpn_train.plateau_rel}),
      shared_field<int>(N, "fvon_warmup_trainings", {&its_train.warmup_calls, &f2f_train.warmup_calls}),
      shared_field<int>(N, "fvon_maintenance_epochs", {&its_train.maintenance_epochs, &f2f_train.maintenance_epochs}),
      field(U, "measurement_fej", up.measurement_fej),
      field(U, "max_clones", up.max_clones),
      field(U, "min_track_length", up.msckf.min_observations),
      field(U, "min_parallax_deg", up.msckf.min_parallax_deg),
      field(U, "sigma_px", up.msckf.sigma_px),
      field(U, "chi2_multiplier", up.msckf.chi2_multiplier),
      field(U, "max_features", up.msckf.max_features),
      field(U, "track_correlation", up.msckf.track_correlation),
      field(U, "covariance_track_correlation", up.msckf.covariance_track_correlation),
      field(U, "covariance_camera_correlation", up.msckf.covariance_camera_correlation),
      field(L, "max_features", o.slam.max_features),
      field(L, "max_init_per_frame", o.slam.max_init_per_frame),
      field(L, "chi2_multiplier", o.slam.updater.chi2_multiplier),
      field(L, "sigma_px", o.slam.updater.sigma_px),
      field(L, "track_correlation", o.slam.updater.track_correlation),
      field(L, "covariance_sigma_px", o.slam.updater.covariance_sigma_px),
      field(L, "state_velocity", o.slam.updater.state_velocity),
      field(L, "further_cameras", o.slam.updater.further_cameras),
      field(C, "extrinsics", cal.extrinsics),
      field(C, "sigma_ext_rot", cal.sigma_ext_rot),
      field(C, "sigma_ext_pos", cal.sigma_ext_pos),
      field(C, "intrinsics", cal.intrinsics),
      field(C, "sigma_focal_px", cal.sigma_focal_px),
      field(C, "sigma_center_px", cal.sigma_center_px),
      field(C, "sigma_distortion", cal.sigma_distortion),
      field(C, "readout", cal.readout),
      field(C, "readout_s", cal.readout_s),
      field(C, "sigma_readout_s", cal.sigma_readout_s),
      field(C, "readout_state_velocity", up.msckf.readout_state_velocity),
      field(C, "imu_intrinsics", cal.imu_intrinsics),
      field(C, "sigma_imu_intrinsics", cal.sigma_imu_intrinsics),
      field(Z, "enabled", o.zupt.enabled),
      field(Z, "max_disparity_px", o.zupt.max_disparity_px),
      field(Z, "sigma_v", o.zupt.sigma_v),
      field(K, "num_features", tr.num_features),
      field(K, "grid_x", tr.grid_x),
      field(K, "grid_y", tr.grid_y),
      field(K, "min_px_dist", tr.min_px_dist),
      field(K, "fast_threshold", tr.fast_threshold),
      field(K, "pyr_levels", tr.pyr_levels),
      field(K, "win_size", tr.win_size),
      field(K, "lk_max_iter", tr.lk_max_iter),
      field(K, "lk_eps", tr.lk_eps),
      field(K, "ransac_px", tr.ransac_px),
      field(K, "forward_backward", tr.forward_backward),
      field(K, "gyro_prior", tr.gyro_prior),
      enum_field<ovton::core::ImageEqualization>(K, "equalization", tr.equalization, parser(kEqualization),
                                                 namer(kEqualization)),
      field(I, "noise_multiplier", o.imu.noise_multiplier),
      field(I, "gravity_mag", o.imu.gravity_mag),
      field(I, "gyroscope_noise_density", o.imu.gyroscope_noise_density),
      field(I, "gyroscope_random_walk", o.imu.gyroscope_random_walk),
      field(I, "accelerometer_noise_density", o.imu.accelerometer_noise_density),
      field(I, "accelerometer_random_walk", o.imu.accelerometer_random_walk),
      enum_field<InitMode>(S, "mode", in.mode, parse_init_mode, [](InitMode m) { return to_string(m); }),
      field(S, "window_s", in.window_s),
      field(S, "max_accel_std", in.max_accel_std),
      field(S, "max_gyro_std", in.max_gyro_std),
      field(S, "sigma_rollpitch", in.sigma_rollpitch),
      field(S, "sigma_yaw", in.sigma_yaw),
      field(S, "sigma_pos", in.sigma_pos),
      field(S, "sigma_vel", in.sigma_vel),
      field(S, "sigma_bg", in.sigma_bg),
      field(S, "sigma_ba", in.sigma_ba),
      field("health", "enabled", o.health.enabled),
      field(S, "still_window_s", in.still_window_s),
      field(S, "still_max_disparity_px", in.still_max_disparity_px),
      field(S, "dyn_window_s", in.dynamic.window_s),
      field(S, "dyn_min_features", in.dynamic.min_features),
      field(S, "dyn_max_features", in.dynamic.max_features),
      field(S, "dyn_min_observations", in.dynamic.min_observations),
      field(S, "dyn_min_disparity_px", in.dynamic.min_disparity_px),
      field(S, "dyn_max_rms_px", in.dynamic.max_rms_px),
      field(S, "dyn_max_sigma_rollpitch_deg", in.dynamic.max_sigma_rollpitch_deg),
      field(S, "dyn_max_sigma_vel", in.dynamic.max_sigma_vel),
      field(S, "dyn_sigma_inflation", in.dynamic.sigma_inflation),
  };
}

void require(bool ok, const std::string &what) {
  if (!ok)
    throw ovton::core::UsageError("estimator option out of range: " + what);
}

} // namespace

namespace {
const std::vector<std::pair<const char *, InitMode>> kInitModes = {{"static", InitMode::Static},
                                                                   {"groundtruth", InitMode::GroundTruth},
                                                                   {"auto", InitMode::Auto},
                                                                   {"dynamic", InitMode::Dynamic}};
} // namespace

std::string to_string(InitMode m) {
  return namer(kInitModes)(m);
}

InitMode parse_init_mode(const std::string &s) {
  for (const auto &[name, m] : kInitModes)
    if (s == name)
      return m;
  throw ovton::core::UsageError("unknown initialisation '" + s + "' (expected static, groundtruth, auto or dynamic)");
}

void apply_mode_spec(const ModeSpec &spec, VioOptions &o) {
  o.td.mode = spec.mode;
  if (spec.process != TdProcess::Auto)
    o.td.process = spec.process;
}

void validate_vio_options(const VioOptions &o) {
  require(o.rig.max_cameras >= 0, "rig.max_cameras must be >= 0 (0: every camera the recording has)");
  const auto &td = o.td;
  require(td.sigma_init_s > 0, "time_offset.sigma_init_s must be > 0");
  require(td.random_walk >= 0 && td.random_walk_tpn >= 0 && td.rate_random_walk >= 0,
          "time_offset random walks must be >= 0");
  require(td.rate_sigma_init > 0, "time_offset.rate_sigma_init must be > 0");
  require(td.per_camera_sigma_init_s > 0 && td.per_camera_random_walk >= 0,
          "time_offset.per_camera_sigma_init_s must be > 0 and per_camera_random_walk >= 0");
  require(o.ton.tpn.td_rate_max >= 0, "time_offset.rate_max must be >= 0");
  require(td.adaptive_block_s >= 0 && td.adaptive_block_s <= 60, "time_offset.adaptive_block_s must lie in [0, 60] s");
  require(td.model_check_window_s > 0 && td.model_check_window_s <= 30,
          "time_offset.model_check_window_s must lie in (0, 30] s");
  require(td.model_check_z > 0 && td.model_check_min_step_s >= 0,
          "time_offset.model_check_z must be > 0 and model_check_min_step_s >= 0");
  require(td.jacobian_rate_window_s >= 0 && td.jacobian_rate_window_s <= 1.0,
          "time_offset.jacobian_rate_window_s must lie in [0, 1] s");
  const auto &u = o.update.msckf;
  const auto &sl = o.slam.updater;
  require(u.td_velocity_debias >= 0 && u.td_velocity_debias <= 10, "time_offset.velocity_debias must lie in [0, 10]");
  require(td.clone_trend_tau_s >= 0 && td.clone_trend_tau_s <= 600,
          "time_offset.clone_trend_tau_s must lie in [0, 600] s");
  require(u.td_velocity_debias == 0 || (u.track_correlation == 0 && sl.track_correlation == 0),
          "time_offset.velocity_debias assumes independent pixel errors: it needs update.track_correlation and "
          "slam.track_correlation 0");
  const auto &n = o.ton;
  require(n.fvon.max_labels >= 1 && n.fvon.min_f2f_labels >= 1, "ton.fvon_max_labels and fvon_min_f2f_labels >= 1");
  for (const auto *t : {&n.fvon.its.train, &n.fvon.f2f.train, &n.tpn.tpn.train}) {
    require(t->max_epochs >= 0, "ton epochs must be >= 0");
    require(t->plateau_epochs >= 0 && t->plateau_rel >= 0, "ton.plateau_epochs and ton.plateau_rel must be >= 0");
    require(t->warmup_calls >= 0 && t->maintenance_epochs >= 0,
            "ton.fvon_warmup_trainings and ton.fvon_maintenance_epochs must be >= 0");
  }
  require(n.tpn.min_labels >= 2, "ton.tpn_min_labels must be >= 2");
  require(n.tpn_label_images >= 1 && n.tpn_label_images <= 200, "ton.tpn_label_images must lie in [1, 200]");
  require(n.fvon.gate_px_s >= 0, "ton.fvon_gate_px_s must be >= 0");
  require(o.update.max_clones >= 3, "update.max_clones must be >= 3");
  require(u.min_observations >= 2, "update.min_track_length must be >= 2");
  require(u.min_parallax_deg >= 0, "update.min_parallax_deg must be >= 0");
  require(u.sigma_px > 0, "update.sigma_px must be > 0");
  require(u.chi2_multiplier > 0, "update.chi2_multiplier must be > 0");
  require(u.max_features >= 0, "update.max_features must be >= 0 (0 = no limit)");
  require(u.covariance_track_correlation >= 0 && u.covariance_track_correlation < 1,
          "update.covariance_track_correlation must lie in [0, 1)");
  require(u.covariance_camera_correlation >= 0 && u.covariance_camera_correlation < 1,
          "update.covariance_camera_correlation must lie in [0, 1)");
  require((u.covariance_track_correlation == 0 && sl.covariance_sigma_px == 0) ||
              (u.track_correlation == 0 && sl.track_correlation == 0),
          "update.covariance_track_correlation and slam.covariance_sigma_px are for the independent weights: they "
          "need update.track_correlation and slam.track_correlation 0");
  require(sl.covariance_sigma_px == 0 || sl.covariance_sigma_px >= (sl.sigma_px > 0 ? sl.sigma_px : u.sigma_px),
          "slam.covariance_sigma_px must be 0 (off) or at least the landmarks' sigma_px");
  require(o.slam.max_features >= 0 && o.slam.max_init_per_frame >= 0 && sl.chi2_multiplier > 0,
          "slam.max_features and slam.max_init_per_frame >= 0, slam.chi2_multiplier > 0");
  const auto &c = o.calibration;
  require(c.sigma_ext_rot > 0 && c.sigma_ext_pos > 0 && c.sigma_focal_px > 0 && c.sigma_center_px > 0 &&
              c.sigma_distortion > 0 && c.sigma_readout_s > 0 && c.sigma_imu_intrinsics > 0,
          "calibration sigmas must be > 0");
  require(std::isfinite(c.readout_s) && std::abs(c.readout_s) < 0.1, "calibration.readout_s must be in (-0.1, 0.1) s");
  require(o.zupt.max_disparity_px >= 0 && o.zupt.sigma_v > 0, "zupt.max_disparity_px >= 0 and zupt.sigma_v > 0");
  require(o.imu.noise_multiplier > 0, "imu.noise_multiplier must be > 0");
  for (const double v : {o.imu.gyroscope_noise_density, o.imu.gyroscope_random_walk, o.imu.accelerometer_noise_density,
                         o.imu.accelerometer_random_walk})
    require(std::isfinite(v) && v >= 0 && v < 10,
            "imu noise densities and random walks must be in [0, 10) (0: the dataset's sensor.yaml)");
  // Physical ranges: gravity 0 would let the accel bias absorb 9.8 m/s^2.
  require(o.imu.gravity_mag > 0, "imu.gravity_mag must be > 0");
  require(o.imu.gravity_mag <= 100, "imu.gravity_mag must be <= 100 m/s^2");
  require(std::abs(td.init_s) <= 10, "time_offset.init_s must be within +-10 s");
  require(td.search.range_s > 0 && td.search.range_s <= 1, "time_offset.search_range_s must be in (0, 1]");
  const auto &i = o.init;
  require(i.window_s > 0, "init.window_s must be > 0");
  require(i.window_s <= 60, "init.window_s must be <= 60 s");
  require(i.max_accel_std > 0 && i.max_gyro_std > 0, "init.max_accel_std and init.max_gyro_std must be > 0");
  require(i.sigma_rollpitch > 0 && i.sigma_yaw > 0 && i.sigma_pos > 0 && i.sigma_vel > 0 && i.sigma_bg > 0 &&
              i.sigma_ba > 0,
          "init sigmas must be > 0");
  const auto &dy = i.dynamic;
  require(i.still_window_s > 0 && i.still_max_disparity_px > 0 && dy.window_s > 0,
          "init.still_window_s, still_max_disparity_px and dyn_window_s must be > 0");
  require(dy.min_features >= 3 && dy.max_features >= dy.min_features && dy.min_observations >= 2,
          "init.dyn_min_features >= 3, dyn_max_features >= dyn_min_features, dyn_min_observations >= 2");
  require(dy.min_disparity_px >= 0 && dy.max_rms_px > 0 && dy.max_sigma_rollpitch_deg > 0 && dy.max_sigma_vel > 0 &&
              dy.sigma_inflation > 0,
          "init.dyn_* thresholds must be > 0");
  const auto &t = o.track;
  require(t.num_features > 0 && t.grid_x > 0 && t.grid_y > 0, "tracker.num_features, grid_x and grid_y must be > 0");
  require(t.win_size >= 3 && t.pyr_levels >= 0 && t.min_px_dist >= 0 && t.ransac_px > 0,
          "tracker.win_size >= 3, pyr_levels >= 0, min_px_dist >= 0, ransac_px > 0");
  require(t.lk_max_iter > 0 && t.lk_eps > 0, "tracker.lk_max_iter and lk_eps must be > 0");
}

VioOptions load_vio_options(const std::string &file, std::ostream *print) {
  VioOptions o;
  o.source = file;
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::BadFile &) {
    throw ovton::core::DataError(file, "cannot open estimator config");
  } catch (const YAML::Exception &e) {
    throw ovton::core::DataError(file, e.mark.line + 1, "unreadable YAML: " + e.msg);
  }
  if (root.IsNull())
    throw ovton::core::DataError(file, "empty estimator config");
  if (!root.IsMap())
    throw ovton::core::DataError(file, "expected a YAML mapping of sections (time_offset, ton, update, ...)");
  const std::vector<Field> table = fields(o);
  std::set<std::string> sections_seen;
  for (const auto &sec : root) {
    const std::string section = ovton::core::yaml_as<std::string>(sec.first, file, "section name");
    if (!sections_seen.insert(section).second)
      throw ovton::core::DataError(file, line_of(sec.first), "duplicate section '" + section + "'");
    bool known = false;
    for (const Field &f : table)
      known = known || section == f.section;
    if (!known)
      throw ovton::core::DataError(
          file, line_of(sec.first),
          "unknown section '" + section +
              "' (expected time_offset, ton, update, slam, calibration, zupt, tracker, imu, init or health)");
    if (!sec.second.IsMap())
      throw ovton::core::DataError(file, line_of(sec.first), "section '" + section + "' must be a mapping of keys");
    std::set<std::string> keys_seen;
    for (const auto &kv : sec.second) {
      const std::string key = ovton::core::yaml_as<std::string>(kv.first, file, "key");
      if (!keys_seen.insert(key).second)
        throw ovton::core::DataError(file, line_of(kv.first), "duplicate key '" + section + "." + key + "'");
      const Field *match = nullptr;
      for (const Field &f : table)
        if (section == f.section && key == f.key)
          match = &f;
      if (!match)
        throw ovton::core::DataError(file, line_of(kv.first), "unknown key '" + section + "." + key + "'");
      match->read(kv.second, file);
    }
  }
  try {
    validate_vio_options(o);
  } catch (const ovton::core::UsageError &e) {
    throw ovton::core::DataError(file, e.what());
  }
  if (print)
    print_vio_options(o, *print);
  return o;
}

void print_vio_options(const VioOptions &o_in, std::ostream &os) {
  VioOptions o = o_in; // the field table binds by reference
  os << "estimator options" << (o.source.empty() ? " (defaults)" : " from " + o.source) << ":\n";
  std::string section;
  for (const Field &f : fields(o)) {
    if (section != f.section) {
      section = f.section;
      os << "  " << section << ":\n";
    }
    os << "    " << f.key << ": ";
    f.print(os);
    os << "\n";
  }
}

} // namespace ovton::msckf
