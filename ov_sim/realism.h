#pragma once
// Realism presets of `ovton simulate --realism` (docs/simulate.md, "Realism"):
//  - clean: the plain renderer (blotch texture wall to wall, instantaneous images with 1.5 grey levels
//    of noise, the ADIS16448 datasheet IMU). Kept byte for byte: regression tests rely on it.
//  - euroc: tuned on the real V1_01 moving cut with `ovton trackstats` (plain room with textured objects, lamps,
//    auto-exposure with motion blur, PSF, vignetting, shot and read noise, 8 bits) and an IMU error model measured
//    on the real V1_01 log against its ground truth.
//  - harsh: euroc with longer exposures, more noise, flicker and less texture.
#include <string>
#include <vector>

namespace ovton::sim {

struct SimOptions;

std::vector<std::string> realism_presets();

/// Sets the scene texture, renderer, camera effects and IMU error options of `opt` to a preset and records its
/// name in opt.realism. Other options (trajectory, offset, seed, calibration, planted effects) are untouched.
/// Throws UsageError for an unknown name.
void apply_realism(const std::string &preset, SimOptions &opt);

} // namespace ovton::sim
