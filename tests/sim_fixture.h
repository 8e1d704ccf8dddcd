#pragma once
// Data for whole-run tests: a feature-level simulated flight (no images: fast) written to a folder, and the options
// such a run starts from (ground-truth initialisation, the simulation's pixel noise).
#include "ov_core/io/dataset.h"
#include "ov_msckf_ton/core/vio_options.h"
#include "ov_sim/simulator.h"

#include <string>

namespace ovtest {

/// Writes the built-in flight as features.csv (`pixel_noise` px) into `dir` and loads it.
inline ovton::core::Dataset feature_flight(const std::string &dir, double duration_s, unsigned seed, double pixel_noise,
                                           double agility = 0.0) {
  ovton::sim::SimOptions so;
  so.out_dir = dir;
  so.duration_s = duration_s;
  so.seed = seed;
  so.agility = agility;
  so.features_only = true;
  so.features.pixel_noise = pixel_noise;
  ovton::sim::write_simulation(so);
  return ovton::core::load_dataset(dir);
}

/// Options of a run on such a flight: `mode`, ground-truth initialisation, sigma_px matching the data's noise, and no
/// coarse t_d search (the filter on its own, from the configured t_d).
inline ovton::msckf::VioOptions gt_run_options(ovton::msckf::TdMode mode, double sigma_px) {
  ovton::msckf::VioOptions opt;
  opt.td.mode = mode;
  opt.td.search.enabled = false;
  opt.init.mode = ovton::msckf::InitMode::GroundTruth;
  opt.update.msckf.sigma_px = sigma_px;
  return opt;
}

/// A stereo render of the built-in flight (clean images, agility 1: on the gentle flight t_d's sigma stays ~1.5 ms
/// after 12 s) with cam1 on its own clock; 1.5 s of rows after the 10 s mark.
inline ovton::core::Dataset cam1_clock_render(const std::string &dir, double td0_s, double td1_s, double td1_bias) {
  ovton::sim::SimOptions so;
  so.out_dir = dir;
  so.duration_s = 11.6;
  so.agility = 1.0;
  so.seed = 5;
  so.cameras = 2;
  so.td.td0_s = td0_s;
  so.cam1_own_clock = true;
  so.cam1_td0_s = td1_s;
  so.cam1_td_bias_s_per_s = td1_bias;
  ovton::sim::write_simulation(so);
  return ovton::core::load_dataset(dir);
}

} // namespace ovtest
