#include "ov_msckf_ton/core/vio_options.h"
#include "ov_core/types/errors.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <functional>
#include <map>
#include <ostream>

namespace ov_msckf_ton {

namespace {

/// One table of (key -> reader, printer) so that keys are parsed in exactly one place and printed from the same.
struct Field {
  std::function<void(const YAML::Node &, const std::string &)> read;
  std::function<void(std::ostream &)> print;
};

template <typename T> Field field(T &ref, const char *key) {
  return {[&ref, key](const YAML::Node &n, const std::string &file) {
            try {
              ref = n.as<T>();
            } catch (const YAML::Exception &e) {
              throw ov_core::DataError(file, e.mark.line + 1, std::string("bad value for '") + key + "': " + e.msg);
            }
            if constexpr (std::is_floating_point_v<T>)
              if (!std::isfinite(ref))
                throw ov_core::DataError(file, std::string("non-finite value for '") + key + "'");
          },
          [&ref](std::ostream &os) { os << ref; }};
}

std::map<std::string, Field> fields(VioOptions &o) {
  std::map<std::string, Field> f;
  f["td_init_s"] = field(o.td_init_s, "td_init_s");
  f["td_sigma_init_s"] = field(o.td_sigma_init_s, "td_sigma_init_s");
  f["td_random_walk"] = field(o.td_random_walk, "td_random_walk");
  f["td_random_walk_tpn"] = field(o.td_random_walk_tpn, "td_random_walk_tpn");
  f["fvon_max_labels"] = field(o.fvon_max_labels, "fvon_max_labels");
  f["fvon_min_f2f_labels"] = field(o.fvon_min_f2f_labels, "fvon_min_f2f_labels");
  f["fvon_gate_px_s"] = field(o.fvon_gate_px_s, "fvon_gate_px_s");
  f["its_epochs"] = field(o.its_epochs, "its_epochs");
  f["f2f_epochs"] = field(o.f2f_epochs, "f2f_epochs");
  f["tpn_epochs"] = field(o.tpn_epochs, "tpn_epochs");
  f["tpn_min_labels"] = field(o.tpn_min_labels, "tpn_min_labels");
  f["td_rate_max"] = field(o.td_rate_max, "td_rate_max");
  f["sir_velocity"] = field(o.sir_velocity, "sir_velocity");
  f["sir_first_velocity"] = field(o.sir_first_velocity, "sir_first_velocity");
  f["measurement_fej"] = field(o.measurement_fej, "measurement_fej");
  f["tpn_start_sigma_s"] = field(o.tpn_start_sigma_s, "tpn_start_sigma_s");
  f["max_clones"] = field(o.max_clones, "max_clones");
  f["min_track_length"] = field(o.min_track_length, "min_track_length");
  f["min_parallax_deg"] = field(o.min_parallax_deg, "min_parallax_deg");
  f["sigma_px"] = field(o.sigma_px, "sigma_px");
  f["chi2_multiplier"] = field(o.chi2_multiplier, "chi2_multiplier");
  f["max_features_per_update"] = field(o.max_features_per_update, "max_features_per_update");
  f["zupt"] = field(o.zupt, "zupt");
  f["zupt_max_disparity_px"] = field(o.zupt_max_disparity_px, "zupt_max_disparity_px");
  f["zupt_sigma_v"] = field(o.zupt_sigma_v, "zupt_sigma_v");
  f["num_features"] = field(o.track.num_features, "num_features");
  f["grid_x"] = field(o.track.grid_x, "grid_x");
  f["grid_y"] = field(o.track.grid_y, "grid_y");
  f["min_px_dist"] = field(o.track.min_px_dist, "min_px_dist");
  f["fast_threshold"] = field(o.track.fast_threshold, "fast_threshold");
  f["pyr_levels"] = field(o.track.pyr_levels, "pyr_levels");
  f["win_size"] = field(o.track.win_size, "win_size");
  f["ransac_px"] = field(o.track.ransac_px, "ransac_px");
  f["imu_noise_multiplier"] = field(o.imu_noise_multiplier, "imu_noise_multiplier");
  f["gravity_mag"] = field(o.gravity_mag, "gravity_mag");
  f["init_window_s"] = field(o.init_window_s, "init_window_s");
  f["init_max_accel_std"] = field(o.init_max_accel_std, "init_max_accel_std");
  f["init_max_gyro_std"] = field(o.init_max_gyro_std, "init_max_gyro_std");
  f["init_sigma_rollpitch"] = field(o.init_sigma_rollpitch, "init_sigma_rollpitch");
  f["init_sigma_yaw"] = field(o.init_sigma_yaw, "init_sigma_yaw");
  f["init_sigma_pos"] = field(o.init_sigma_pos, "init_sigma_pos");
  f["init_sigma_vel"] = field(o.init_sigma_vel, "init_sigma_vel");
  f["init_sigma_bg"] = field(o.init_sigma_bg, "init_sigma_bg");
  f["init_sigma_ba"] = field(o.init_sigma_ba, "init_sigma_ba");
  return f;
}

} // namespace

VioOptions load_vio_options(const std::string &file, std::ostream *print) {
  VioOptions o;
  o.source = file;
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::BadFile &) {
    throw ov_core::DataError(file, "cannot open estimator config");
  } catch (const YAML::Exception &e) {
    throw ov_core::DataError(file, e.mark.line + 1, "unreadable YAML: " + e.msg);
  }
  if (!root.IsMap())
    throw ov_core::DataError(file, "expected a YAML mapping");
  auto table = fields(o);
  for (const auto &kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (key == "td_mode") {
      o.td_mode = parse_td_mode(kv.second.as<std::string>());
    } else if (key == "init_mode") {
      const std::string m = kv.second.as<std::string>();
      if (m != "static" && m != "groundtruth")
        throw ov_core::DataError(file, kv.first.Mark().line + 1, "init_mode must be static or groundtruth");
      o.init_mode = m == "static" ? InitMode::Static : InitMode::GroundTruth;
    } else if (auto it = table.find(key); it != table.end()) {
      it->second.read(kv.second, file);
    } else {
      throw ov_core::DataError(file, kv.first.Mark().line + 1, "unknown key '" + key + "'");
    }
  }
  if (o.sir_velocity != "backward" && o.sir_velocity != "central")
    throw ov_core::DataError(file, "sir_velocity must be backward or central");
  if (o.sir_first_velocity != "none" && o.sir_first_velocity != "next")
    throw ov_core::DataError(file, "sir_first_velocity must be none or next");
  if (!(o.min_parallax_deg >= 0))
    throw ov_core::DataError(file, "min_parallax_deg must be >= 0");
  if (o.max_clones < 3)
    throw ov_core::DataError(file, "max_clones must be at least 3");
  if (o.sigma_px <= 0 || o.td_sigma_init_s <= 0)
    throw ov_core::DataError(file, "sigma_px and td_sigma_init_s must be positive");
  if (o.fvon_max_labels < 1 || o.fvon_min_f2f_labels < 1 || o.its_epochs < 0 || o.f2f_epochs < 0 || o.tpn_epochs < 0 ||
      o.tpn_min_labels < 2 || o.td_rate_max < 0 || o.fvon_gate_px_s < 0)
    throw ov_core::DataError(file, "network options out of range (labels >= 1, tpn_min_labels >= 2, epochs, "
                                   "td_rate_max and fvon_gate_px_s >= 0)");
  if (print)
    print_vio_options(o, *print);
  return o;
}

void print_vio_options(const VioOptions &o_in, std::ostream &os) {
  VioOptions o = o_in; // the field table binds by reference
  os << "estimator options" << (o.source.empty() ? " (defaults)" : " from " + o.source) << ":\n";
  os << "  td_mode: " << to_string(o.td_mode) << "\n";
  os << "  init_mode: " << (o.init_mode == InitMode::Static ? "static" : "groundtruth") << "\n";
  for (const auto &[key, f] : fields(o)) {
    os << "  " << key << ": ";
    f.print(os);
    os << "\n";
  }
}

} // namespace ov_msckf_ton
