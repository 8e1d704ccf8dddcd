#pragma once
// The paper's EuRoC protocol on a real folder: image stamps rewritten with a time-offset model, images linked.
#include "ov_sim/td_model.h"
#include <string>

namespace ovton::sim {

struct PerturbOptions {
  std::string in_dir;  ///< EuRoC folder (holding mav0/ or mav0/ itself)
  std::string out_dir; ///< created; must not already hold a mav0/
  TdModelOptions td;   ///< its seed is derived from `seed`
  uint64_t seed = 1;
};

struct PerturbReport {
  size_t n_images = 0;
  double td_first_s = 0.0, td_last_s = 0.0;
};

/// Treats each original stamp as the true IMU-clock instant (EuRoC cam0 and imu0 are hardware-synchronised)
/// and stamps image k with t_k - td(k). Writes OUT/mav0/cam0/data.csv, symlinks cam0/data/<new>.png to the
/// original files, copies every other csv/yaml under mav0/ (other cameras' image folders are linked), writes
/// mav0/td_truth/data.csv and OUT/perturb.yaml.
PerturbReport perturb_dataset(const PerturbOptions &opt);

} // namespace ovton::sim
