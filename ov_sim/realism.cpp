#include "ov_sim/realism.h"
#include "ov_core/types/errors.h"
#include "ov_sim/imu_errors.h"
#include "ov_sim/simulator.h"

namespace ovton::sim {

std::vector<std::string> realism_presets() {
  return {"clean", "euroc", "harsh"};
}

void apply_realism(const std::string &preset, SimOptions &opt) {
  // Every preset starts from the clean defaults, so applying one never inherits another's settings.
  const SimOptions defaults;
  opt.scene.texture = defaults.scene.texture;
  opt.scene.light_ambient = defaults.scene.light_ambient;
  opt.render = defaults.render;
  opt.camera_effects = defaults.camera_effects;
  opt.imu_errors = defaults.imu_errors;
  if (preset == "clean") {
    opt.realism = preset;
    return;
  }
  if (preset != "euroc" && preset != "harsh")
    throw ovton::core::UsageError("unknown realism preset '" + preset + "' (clean, euroc or harsh)");
  // euroc: tuned on ../shared/data/euroc_v1_01_moving (docs/simulate.md has the table and the command).
  opt.scene.texture.style = TextureStyle::Room;
  CameraEffectsOptions &c = opt.camera_effects;
  c.enabled = true;
  opt.imu_errors = euroc_v1_01_imu_errors();
  if (preset == "harsh") {
    opt.scene.texture.density *= 0.6;
    c.scene_exposure_s *= 2.5; // a darker room: auto-exposure opens up to its limit, then gains
    c.ae_max_exposure_s = 0.02;
    c.read_noise_e *= 2.0;
    c.flicker_amplitude = 0.1;
  }
  opt.realism = preset;
}

} // namespace ovton::sim
