// sim.yaml: every parameter of a simulation and its seed, so that a folder says how it was made.
#include "ov_core/types/errors.h"
#include "ov_sim/simulator.h"

#include <yaml-cpp/yaml.h>

namespace ovton::sim {

std::string sim_yaml(const SimOptions &opt, const Trajectory &traj, const std::string &imu_bias_source) {
  YAML::Emitter e;
  e.SetDoublePrecision(15); // 0.1 prints as 0.1, and every value still reads back unchanged
  e << YAML::BeginMap;
  e << YAML::Key << "generator" << YAML::Value << "ovton simulate";
  e << YAML::Key << "seed" << YAML::Value << opt.seed;
  e << YAML::Key << "trajectory" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "source" << YAML::Value << traj.describe();
  e << YAML::Key << "start_s" << YAML::Value << opt.start_s;
  e << YAML::Key << "duration_s" << YAML::Value << opt.duration_s;
  e << YAML::Key << "knot_dt_s" << YAML::Value << opt.knot_dt_s;
  e << YAML::Key << "align_gt_to" << YAML::Value << (opt.align_gt_to.empty() ? "none" : opt.align_gt_to);
  if (!opt.align_gt_to.empty())
    e << YAML::Key << "align_blend_hz" << YAML::Value << opt.align_blend_hz;
  e << YAML::Key << "t_begin_ns" << YAML::Value << traj.t_begin_ns();
  e << YAML::Key << "t_end_ns" << YAML::Value << traj.t_end_ns();
  e << YAML::EndMap;
  e << YAML::Key << "imu" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "source" << YAML::Value << (opt.imu_from.empty() ? "synthetic" : "real:" + opt.imu_from);
  if (!opt.imu_from.empty()) // where the ground truth's bias columns come from (real_imu.h)
    e << YAML::Key << "bias_truth" << YAML::Value << imu_bias_source;
  e << YAML::Key << "calibration" << YAML::Value << opt.imu_source;
  e << YAML::Key << "rate_hz" << YAML::Value << opt.imu.rate_hz;
  e << YAML::Key << "gyroscope_noise_density" << YAML::Value << opt.imu.gyro_noise_density;
  e << YAML::Key << "gyroscope_random_walk" << YAML::Value << opt.imu.gyro_random_walk;
  e << YAML::Key << "accelerometer_noise_density" << YAML::Value << opt.imu.accel_noise_density;
  e << YAML::Key << "accelerometer_random_walk" << YAML::Value << opt.imu.accel_random_walk;
  {
    // What imu0/sensor.yaml declares (the values above are what the synthesis used for its white noise and walk).
    const ovton::core::ImuCalib d = declared_imu(opt);
    e << YAML::Key << "declared" << YAML::Value << YAML::BeginMap;
    e << YAML::Key << "gyroscope_noise_density" << YAML::Value << d.gyro_noise_density;
    e << YAML::Key << "gyroscope_random_walk" << YAML::Value << d.gyro_random_walk;
    e << YAML::Key << "accelerometer_noise_density" << YAML::Value << d.accel_noise_density;
    e << YAML::Key << "accelerometer_random_walk" << YAML::Value << d.accel_random_walk;
    e << YAML::EndMap;
  }
  e << YAML::Key << "noise" << YAML::Value << opt.imu_noise;
  e << YAML::Key << "bias_walk" << YAML::Value << opt.imu_bias_walk;
  e << YAML::Key << "gyro_scale_error" << YAML::Value << opt.gyro_scale; // planted: the gyro reads (1 + s)·ω
  const auto mat = [&](const char *key, const Eigen::Matrix3d &M) {
    e << YAML::Key << key << YAML::Value << YAML::Flow
      << std::vector<double>{M(0, 0), M(0, 1), M(0, 2), M(1, 0), M(1, 1), M(1, 2), M(2, 0), M(2, 1), M(2, 2)};
  };
  // Planted: the gyro reads (1 + s)·(I + M_g)·ω, the accelerometer (I + M_a)·f (row-major).
  mat("gyro_scale_misalignment_error", opt.gyro_M);
  mat("accel_scale_misalignment_error", opt.accel_M);
  {
    const ImuErrorModel &m = opt.imu_errors;
    e << YAML::Key << "errors" << YAML::Value << YAML::BeginMap;
    e << YAML::Key << "enabled" << YAML::Value << (m.enabled && opt.imu_from.empty());
    if (m.enabled && opt.imu_from.empty()) {
      const auto vec = [&](const char *key, const Eigen::Vector3d &v) {
        e << YAML::Key << key << YAML::Value << YAML::Flow << std::vector<double>{v.x(), v.y(), v.z()};
      };
      const Eigen::Matrix3d &S = m.gyro_scale_misalignment;
      e << YAML::Key << "gyro_scale_misalignment" << YAML::Value << YAML::Flow
        << std::vector<double>{S(0, 0), S(0, 1), S(0, 2), S(1, 0), S(1, 1), S(1, 2), S(2, 0), S(2, 1), S(2, 2)};
      vec("gyro_bias0", m.gyro_bias0);
      vec("accel_bias0", m.accel_bias0);
      e << YAML::Key << "flight_spectrum" << YAML::Value << YAML::BeginSeq;
      for (const NoiseBand &b : m.flight_spectrum) {
        e << YAML::Flow << YAML::BeginMap;
        e << YAML::Key << "band_hz" << YAML::Value << YAML::Flow << std::vector<double>{b.low_hz, b.high_hz};
        vec("gyro", b.gyro);
        vec("accel", b.accel);
        e << YAML::EndMap;
      }
      e << YAML::EndSeq;
      e << YAML::Key << "ground_gyro_ratio" << YAML::Value << m.ground_gyro_ratio;
      e << YAML::Key << "ground_accel_ratio" << YAML::Value << m.ground_accel_ratio;
      e << YAML::Key << "flight_speed_mps" << YAML::Value << m.flight_speed_mps;
    }
    e << YAML::EndMap;
  }
  e << YAML::Key << "gravity_W" << YAML::Value << YAML::Flow << std::vector<double>{0.0, 0.0, -9.81};
  e << YAML::EndMap;
  e << YAML::Key << "camera" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "calibration" << YAML::Value << opt.cam_source;
  e << YAML::Key << "rate_hz" << YAML::Value << opt.cam.rate_hz;
  e << YAML::Key << "first_image_s" << YAML::Value << opt.first_image_s;
  e << YAML::Key << "output" << YAML::Value << (opt.no_images ? "none" : (opt.features_only ? "features" : "images"));
  // Planted camera effects (docs/simulate.md): what the data carry and cam0/sensor.yaml does not say.
  e << YAML::Key << "rolling_shutter_readout_s" << YAML::Value << opt.readout_s;
  e << YAML::Key << "rolling_shutter_convention" << YAML::Value
    << "row v exposed at the image's IMU-clock instant + v/height * readout; the stamp belongs to row 0";
  e << YAML::Key << "focal_error" << YAML::Value << opt.focal_error;
  const ovton::core::CameraCalib tc = true_camera(opt);
  // Planted extrinsic error: the data use R_BC_true = Exp(rot)·R_BC, p_BC_true = p_BC + trans (body frame).
  e << YAML::Key << "extrinsic_rotation_error_rad" << YAML::Value << YAML::Flow
    << std::vector<double>{opt.extrinsic_rot.x(), opt.extrinsic_rot.y(), opt.extrinsic_rot.z()};
  e << YAML::Key << "extrinsic_translation_error_m" << YAML::Value << YAML::Flow
    << std::vector<double>{opt.extrinsic_trans.x(), opt.extrinsic_trans.y(), opt.extrinsic_trans.z()};
  e << YAML::Key << "true_intrinsics" << YAML::Value << YAML::Flow
    << std::vector<double>{tc.intrinsics(0), tc.intrinsics(1), tc.intrinsics(2), tc.intrinsics(3)};
  e << YAML::EndMap;
  e << YAML::Key << "time_offset" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "convention" << YAML::Value << "t_imu = t_cam + td";
  e << YAML::Key << "model" << YAML::Value << to_string(opt.td.kind);
  e << YAML::Key << "td0_s" << YAML::Value << opt.td.td0_s;
  e << YAML::Key << "bias_s_per_s" << YAML::Value << opt.td.bias_s_per_s;
  e << YAML::Key << "noise_s_per_sqrt_s" << YAML::Value << opt.td.noise_s_per_sqrt_s;
  e << YAML::Key << "wander_amplitude_s" << YAML::Value << opt.td.wander_amplitude_s;
  e << YAML::Key << "wander_period_s" << YAML::Value << opt.td.wander_period_s;
  if (opt.cameras >= 2 && opt.cam1_own_clock) { // only then: every other folder's sim.yaml stays as it was
    e << YAML::Key << "cam1_own_clock" << YAML::Value << YAML::BeginMap;
    e << YAML::Key << "td0_s" << YAML::Value << opt.cam1_td0_s;
    e << YAML::Key << "bias_s_per_s" << YAML::Value << opt.cam1_td_bias_s_per_s;
    e << YAML::EndMap;
  }
  e << YAML::EndMap;
  e << YAML::Key << "scene" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "margin_xy_m" << YAML::Value << opt.scene.margin_xy_m;
  e << YAML::Key << "margin_below_m" << YAML::Value << opt.scene.margin_below_m;
  e << YAML::Key << "margin_above_m" << YAML::Value << opt.scene.margin_above_m;
  e << YAML::Key << "num_boxes" << YAML::Value << opt.scene.num_boxes;
  e << YAML::Key << "box_clearance_m" << YAML::Value << opt.scene.box_clearance_m;
  e << YAML::Key << "texel_m" << YAML::Value << opt.scene.texture.texel_m;
  e << YAML::Key << "feature_min_m" << YAML::Value << opt.scene.texture.feature_min_m;
  e << YAML::Key << "feature_max_m" << YAML::Value << opt.scene.texture.feature_max_m;
  e << YAML::Key << "render_noise_sigma" << YAML::Value << opt.render.noise_sigma;
  e << YAML::Key << "texture" << YAML::Value << to_string(opt.scene.texture.style);
  if (opt.scene.texture.style == TextureStyle::Room) {
    e << YAML::Key << "texture_density" << YAML::Value << opt.scene.texture.density;
    e << YAML::Key << "texture_grain" << YAML::Value << opt.scene.texture.grain;
    e << YAML::Key << "texture_weave" << YAML::Value << opt.scene.texture.weave;
    e << YAML::Key << "texture_stain" << YAML::Value << opt.scene.texture.stain;
    e << YAML::Key << "texture_from" << YAML::Value << (opt.texture_from.empty() ? "procedural" : opt.texture_from);
    e << YAML::Key << "light_ambient" << YAML::Value << opt.scene.light_ambient;
  }
  e << YAML::EndMap;
  e << YAML::Key << "realism" << YAML::Value << opt.realism;
  const CameraEffectsOptions &c = opt.camera_effects;
  e << YAML::Key << "camera_effects" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "enabled" << YAML::Value << c.enabled;
  if (c.enabled) {
    e << YAML::Key << "stamp_convention" << YAML::Value
      << "the image stamp (and td_truth) is the middle of the exposure; row v of a rolling shutter is exposed "
         "around its own instant";
    e << YAML::Key << "exposure_s" << YAML::Value << c.exposure_s;
    e << YAML::Key << "auto_exposure" << YAML::Value << c.auto_exposure;
    e << YAML::Key << "ae_target" << YAML::Value << c.ae_target;
    e << YAML::Key << "ae_min_exposure_s" << YAML::Value << c.ae_min_exposure_s;
    e << YAML::Key << "ae_max_exposure_s" << YAML::Value << c.ae_max_exposure_s;
    e << YAML::Key << "ae_max_gain" << YAML::Value << c.ae_max_gain;
    e << YAML::Key << "ae_rate" << YAML::Value << c.ae_rate;
    e << YAML::Key << "scene_exposure_s" << YAML::Value << c.scene_exposure_s;
    e << YAML::Key << "blur_step_px" << YAML::Value << c.blur_step_px;
    e << YAML::Key << "blur_max_samples" << YAML::Value << c.blur_max_samples;
    e << YAML::Key << "vignetting" << YAML::Value << c.vignetting;
    e << YAML::Key << "psf_sigma_px" << YAML::Value << c.psf_sigma_px;
    e << YAML::Key << "full_well_e" << YAML::Value << c.full_well_e;
    e << YAML::Key << "read_noise_e" << YAML::Value << c.read_noise_e;
    e << YAML::Key << "flicker_amplitude" << YAML::Value << c.flicker_amplitude;
    e << YAML::Key << "flicker_hz" << YAML::Value << c.flicker_hz;
    e << YAML::Key << "quantisation_bits" << YAML::Value << 8;
  }
  e << YAML::EndMap;
  if (opt.features_only) {
    e << YAML::Key << "features" << YAML::Value << YAML::BeginMap;
    e << YAML::Key << "max_tracks" << YAML::Value << opt.features.max_tracks;
    e << YAML::Key << "grid" << YAML::Value << YAML::Flow
      << std::vector<int>{opt.features.grid_cols, opt.features.grid_rows};
    e << YAML::Key << "pixel_noise" << YAML::Value << opt.features.pixel_noise;
    e << YAML::Key << "mean_track_length" << YAML::Value << opt.features.mean_track_length;
    e << YAML::Key << "landmarks_per_m2" << YAML::Value << opt.features.landmarks_per_m2;
    e << YAML::EndMap;
  }
  e << YAML::EndMap;
  return std::string(e.c_str()) + "\n";
}

} // namespace ovton::sim
