// `ovton simulate`: synthetic EuRoC-format folder with a known camera-IMU time offset (see docs/simulate.md).
#include "ov_core/io/dataset.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/types/errors.h"
#include "ov_sim/imu_match.h"
#include "ov_sim/real_imu.h"
#include "ov_sim/realism.h"
#include "ov_sim/simulator.h"
#include "tools/cli.h"
#include "tools/commands.h"

#include <algorithm>
#include <boost/program_options.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace ovton::cli {

namespace {

/// Prints a progress line on stderr at most twice a second, and always at the end of a stage.
class ProgressPrinter {
public:
  explicit ProgressPrinter(bool quiet) : quiet_(quiet), t0_(std::chrono::steady_clock::now()) {}
  void operator()(const std::string &stage, size_t done, size_t total) {
    if (quiet_)
      return;
    const auto now = std::chrono::steady_clock::now();
    const double el = std::chrono::duration<double>(now - t0_).count();
    if (stage != stage_ || done == total || el - last_ > 0.5) {
      std::fprintf(stderr, "\r%-14s %6zu/%zu  (%.1f s)", stage.c_str(), done, total, el);
      if (done == total)
        std::fprintf(stderr, "\n");
      std::fflush(stderr);
      last_ = el;
      stage_ = stage;
    }
  }

private:
  bool quiet_;
  std::chrono::steady_clock::time_point t0_;
  double last_ = -1.0;
  std::string stage_;
};

/// "x,y,z" -> vector (three numbers); a UsageError naming the option otherwise.
Eigen::Vector3d parse_xyz(const std::string &text, const char *option) {
  Eigen::Vector3d v;
  char c1 = 0, c2 = 0;
  std::istringstream in(text);
  if (!(in >> v.x() >> c1 >> v.y() >> c2 >> v.z()) || c1 != ',' || c2 != ',' || !(in >> std::ws).eof())
    throw ovton::core::UsageError(std::string("--") + option + " expects three numbers 'x,y,z', got '" + text + "'");
  return v;
}

/// Per-axis scale (diagonal, %) and symmetric misalignment (off-diagonal xy, xz, yz, mrad) as the matrix M of a
/// sensor that reads (I + M)·x. The antisymmetric part is left out: for the gyro it is a camera-IMU rotation
/// (--extrinsic-rot-deg plants that).
Eigen::Matrix3d scale_misalignment(const Eigen::Vector3d &scale_pct, const Eigen::Vector3d &mis_mrad) {
  Eigen::Matrix3d M = (scale_pct * 1e-2).asDiagonal();
  M(0, 1) = M(1, 0) = mis_mrad.x() * 1e-3;
  M(0, 2) = M(2, 0) = mis_mrad.y() * 1e-3;
  M(1, 2) = M(2, 1) = mis_mrad.z() * 1e-3;
  return M;
}

std::map<std::string, uintmax_t> sizes_by_part(const fs::path &mav0) {
  std::map<std::string, uintmax_t> s;
  for (const auto &e : fs::recursive_directory_iterator(mav0))
    if (e.is_regular_file()) {
      const fs::path rel = fs::relative(e.path(), mav0);
      std::string part = rel.begin()->string();
      if (part == "cam0")
        part = rel.string().rfind("cam0/data/", 0) == 0 ? "cam0 images" : "cam0 lists";
      s[part] += e.file_size();
    }
  return s;
}

} // namespace

int cmd_simulate(const Args &args) {
  po::options_description desc(
      "ovton simulate: write a synthetic EuRoC-format folder (images or features, IMU, ground truth, true offset)\n"
      "Convention: t_imu = t_cam + td; image k shows the scene at IMU time t_k and is stamped t_k - td(k)");
  ovton::sim::SimOptions o;
  std::string out, gt, td_model = "constant", cam_yaml, imu_yaml;
  double td0_ms = 10.0, td_bias = 0.1, td_noise = 0.1, readout_ms = 0.0, focal_error_pct = 0.0, gyro_scale_pct = 0.0;
  int bench_frames = 100;
  std::string realism = "euroc", texture;
  double exposure_ms = 0.0;
  double td_wander_ms = 4.0, td_wander_period_s = 10.0;
  std::string gyro_axes = "0,0,0", gyro_mis = "0,0,0", accel_axes = "0,0,0", accel_mis = "0,0,0";
  std::string ext_rot = "0,0,0", ext_trans = "0,0,0";
  desc.add_options()("help,h", "this help")                                                      //
      ("out,o", po::value(&out), "output folder (mav0/ and sim.yaml are written inside)")        //
      ("gt", po::value(&gt), "ground-truth trajectory to follow (EuRoC .txt/.csv, project CSV)") //
      ("align-gt", po::value(&o.align_gt_to),
       "move --gt onto the real IMU of this EuRoC folder first (its clock, axes, gravity; the lever arm against the "
       "folder's ground truth) and keep only its motion above --align-blend-hz on top of that ground truth: with a "
       "200 Hz pose file and --knot-dt-s 0.03, semi-real images follow the motion the real IMU saw "
       "(docs/simulate.md, \"Semi-real folders\")") //
      ("align-blend-hz", po::value(&o.align_blend_hz)->default_value(1.5),
       "--align-gt: below this frequency the folder's ground truth, above it --gt (0: --gt alone)")       //
      ("builtin", "follow the built-in Lissajous flight in a 6x6x3 m room (default when --gt is absent)") //
      ("agility", po::value(&o.agility)->default_value(0.0),
       "built-in flight: add faster roll/pitch/yaw oscillations, angular accelerations ~A x 1 rad/s^2 [0-3]") //
      ("start-s", po::value(&o.start_s)->default_value(0.0), "start, seconds after the first gt pose")        //
      ("duration-s", po::value(&o.duration_s)->default_value(20.0), "length [s]")                             //
      ("seed", po::value(&o.seed)->default_value(1), "random seed (same seed, same bytes)")                   //
      ("cameras", po::value(&o.cameras)->default_value(1),
       "1: cam0 alone; 2: a stereo rig, cam1 rendered too with EuRoC's stereo extrinsics (same stamps, own sensor "
       "noise)") //
      ("cam1-td-ms", po::value<double>(),
       "--cameras 2: cam1 on a clock of its own: its image with cam0's stamp shows t_cam + this at the first image "
       "[ms] (whatever cam0's offset does; truth in mav0/td_truth_cam1). Absent: cam1 is triggered with cam0") //
      ("cam1-td-bias-ms-per-s", po::value<double>(),
       "--cameras 2: cam1's own offset grows by this [ms/s] (with --cam1-td-ms; alone: from --td0-ms)")       //
      ("td-model", po::value(&td_model)->default_value("constant"), "constant | drift | wander")              //
      ("td0-ms", po::value(&td0_ms)->default_value(10.0), "offset at the first image [ms]")                   //
      ("td-bias-ms-per-s", po::value(&td_bias)->default_value(0.1), "drift: growth [ms/s]")                   //
      ("td-noise-ms-per-sqrt-s", po::value(&td_noise)->default_value(0.1), "drift: random walk [ms/sqrt(s)]") //
      ("td-wander-ms", po::value(&td_wander_ms)->default_value(4.0),
       "wander: td = td0 + A sin(2 pi t / P), no trend; amplitude A [ms]")                                //
      ("td-wander-period-s", po::value(&td_wander_period_s)->default_value(10.0), "wander: period P [s]") //
      ("readout-ms", po::value(&readout_ms)->default_value(0.0),
       "rolling shutter: row v is exposed at the image's instant + v/height * readout; stamp = row 0 [ms]") //
      ("focal-error-pct", po::value(&focal_error_pct)->default_value(0.0),
       "data made with focal lengths (1 + P/100) x those written to cam0/sensor.yaml [%]") //
      ("gyro-scale-pct", po::value(&gyro_scale_pct)->default_value(0.0),
       "the gyro reads (1 + P/100) x the true rate; imu0/sensor.yaml does not say so [%]") //
      ("gyro-scale-axes-pct", po::value(&gyro_axes)->default_value("0,0,0"),
       "per-axis gyro scale error 'x,y,z': the gyro reads (I + M) w, M's diagonal [%]") //
      ("gyro-misalignment-mrad", po::value(&gyro_mis)->default_value("0,0,0"),
       "gyro axis misalignment 'xy,xz,yz': M's symmetric off-diagonal [mrad]") //
      ("accel-scale-axes-pct", po::value(&accel_axes)->default_value("0,0,0"),
       "per-axis accelerometer scale error 'x,y,z': it reads (I + M) f, f the specific force [%]") //
      ("accel-misalignment-mrad", po::value(&accel_mis)->default_value("0,0,0"),
       "accelerometer axis misalignment 'xy,xz,yz': M's symmetric off-diagonal [mrad]") //
      ("extrinsic-rot-deg", po::value(&ext_rot)->default_value("0,0,0"),
       "camera-IMU rotation error 'x,y,z': data made with R_BC = Exp(r) R_BC(yaml), r in the body frame [deg]") //
      ("extrinsic-trans-mm", po::value(&ext_trans)->default_value("0,0,0"),
       "camera-IMU translation error 'x,y,z': data made with p_BC(yaml) + d, body frame [mm]") //
      ("imu-from", po::value(&o.imu_from),
       "semi-real: take the real IMU log of this EuRoC folder (mav0/imu0/data.csv) or of this imu0 CSV file "
       "(e.g. ../shared/data/euroc_imu0/MH03.csv)") //
      ("realism", po::value(&realism)->default_value("euroc"),
       "clean (blotch texture, instantaneous images, datasheet IMU) | euroc (room texture, auto-exposure with "
       "motion blur, PSF, vignetting, sensor noise; tuned on real V1_01) | harsh")                            //
      ("texture", po::value(&texture), "override the preset's texture: blotches | room")                      //
      ("texture-density", po::value<double>(), "room texture: share of faces covered by textured patches")    //
      ("texture-grain", po::value<double>(), "room texture: grain of plain surfaces [grey levels]")           //
      ("texture-weave", po::value<double>(), "room texture: ~2 cm weave, relative to the grain")              //
      ("texture-from", po::value(&o.texture_from), "room texture: posters cut from this EuRoC folder's cam0") //
      ("exposure-ms", po::value(&exposure_ms), "fixed exposure [ms] (turns auto-exposure off)")               //
      ("no-blur", "one rendering per image at the middle of the exposure (no motion blur)")                   //
      ("psf-px", po::value<double>(), "optics blur sigma [px]")                                               //
      ("vignetting", po::value<double>(), "brightness lost at the image corners [0-1)")                       //
      ("full-well-e", po::value<double>(), "electrons at full scale, gain 1 (shot noise)")                    //
      ("read-noise-e", po::value<double>(), "read noise [electrons]")                                         //
      ("flicker", po::value<double>(), "relative lamp flicker at 100 Hz (0 = steady)")                        //
      ("features-only", "write mav0/cam0/features.csv (timestamp_ns,feature_id,u,v) instead of images")       //
      ("no-images", "write no images and no features (IMU, ground truth, stamps)")                            //
      ("no-imu-noise", "noise-free IMU (no white noise, no bias walk)")                                       //
      ("imu-errors", po::value<std::string>(),
       "override the preset's IMU errors: euroc (the model measured on real V1_01) | none (datasheet noise only)") //
      ("imu-errors-drop", po::value<std::string>(),
       "leave parts of the IMU error model out (ablations), comma separated: scale, turn-on, slow (< 2 Hz), mid, "
       "vibration (>= 10 Hz), vibration-gyro, vibration-accel") //
      ("imu-declare", po::value<std::string>(),
       "what imu0/sensor.yaml says of the noise: fitted (default: the realistic IMU's Allan fit, also for "
       "--imu-from) | datasheet")                                                                           //
      ("knot-dt-s", po::value(&o.knot_dt_s)->default_value(0.1), "B-spline knot spacing of the gt fit [s]") //
      ("cam-yaml", po::value(&cam_yaml), "EuRoC cam0/sensor.yaml to use (default: built-in EuRoC cam0)")    //
      ("imu-yaml", po::value(&imu_yaml), "EuRoC imu0/sensor.yaml to use (default: built-in ADIS16448)")     //
      ("pixel-noise", po::value(&o.features.pixel_noise)->default_value(1.0), "features-only: noise [px]")  //
      ("max-tracks", po::value(&o.features.max_tracks)->default_value(200), "features-only: live tracks")   //
      ("match-imu", "measure the real IMU log of --imu-from against --gt (noise, biases, scale, the ground truth's "
                    "time shift and frame rotation) and print it; no folder is written")                   //
      ("benchmark", "measure render speed (one core) and disk size per minute; --out optional")            //
      ("benchmark-frames", po::value(&bench_frames)->default_value(100), "frames rendered by --benchmark") //
      ("force", "replace OUT/mav0 if it exists")                                                           //
      ("quiet,q", "no progress output");
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0; // --help
  if (vm.count("match-imu") && !o.align_gt_to.empty())
    throw ovton::core::UsageError("--match-imu measures --gt as it is: leave out --align-gt");
  if (vm.count("match-imu")) {
    if (gt.empty() || o.imu_from.empty())
      throw ovton::core::UsageError("--match-imu needs --gt and --imu-from (a real log and its ground truth)");
    const ovton::sim::RealImu real = ovton::sim::load_real_imu(o.imu_from);
    ovton::sim::ImuMatchOptions mo;
    mo.knot_dt_s = o.knot_dt_s;
    const std::string yaml =
        "imu_log: " + o.imu_from + "\nground_truth: " + gt + "\n" +
        ovton::sim::imu_match_yaml(ovton::sim::match_imu(real.imu, ovton::core::read_trajectory(gt), mo));
    std::cout << yaml;
    if (!out.empty()) {
      fs::create_directories(out);
      std::ofstream f(fs::path(out) / "imu_match.yaml");
      f << yaml;
      if (!f)
        throw ovton::core::DataError((fs::path(out) / "imu_match.yaml").string(), "cannot write");
    }
    return 0;
  }
  const bool bench = vm.count("benchmark") > 0;
  if (out.empty() && !bench)
    throw ovton::core::UsageError("--out is required");
  if (vm.count("builtin") && !gt.empty())
    throw ovton::core::UsageError("--gt and --builtin are exclusive");
  if (vm.count("features-only") && vm.count("no-images"))
    throw ovton::core::UsageError("--features-only and --no-images are exclusive");
  if (!o.align_gt_to.empty() && gt.empty())
    throw ovton::core::UsageError("--align-gt needs --gt (the reference to align)");
  if (!vm["align-blend-hz"].defaulted() && o.align_gt_to.empty())
    throw ovton::core::UsageError("--align-blend-hz applies with --align-gt");
  if (!o.imu_from.empty() && gt.empty())
    throw ovton::core::UsageError("--imu-from needs --gt with the ground truth of the same sequence");
  if (o.agility != 0.0 && !gt.empty())
    throw ovton::core::UsageError("--agility applies to the built-in flight, not to --gt");
  o.gt_file = gt;
  ovton::sim::apply_realism(realism, o);
  {
    // Hand overrides of the preset; sim.yaml records every value, and the preset's name says it was modified.
    bool modified = false;
    auto &c = o.camera_effects;
    const auto need_effects = [&](const char *name) {
      if (!c.enabled)
        throw ovton::core::UsageError(std::string("--") + name + " needs camera effects (--realism euroc or harsh)");
      modified = true;
    };
    const auto camera_option = [&](const char *name, double &field) {
      if (vm.count(name)) {
        need_effects(name);
        field = vm[name].as<double>();
      }
    };
    if (vm.count("texture")) {
      o.scene.texture.style = ovton::sim::parse_texture_style(texture);
      modified = true;
    }
    const auto scene_option = [&](const char *name, double &field) {
      if (vm.count(name)) {
        field = vm[name].as<double>();
        modified = true;
      }
    };
    scene_option("texture-density", o.scene.texture.density);
    scene_option("texture-grain", o.scene.texture.grain);
    scene_option("texture-weave", o.scene.texture.weave);
    if (vm.count("exposure-ms")) {
      need_effects("exposure-ms");
      c.exposure_s = exposure_ms * 1e-3;
      c.auto_exposure = false;
    }
    if (vm.count("no-blur")) {
      need_effects("no-blur");
      c.blur_max_samples = 1;
    }
    camera_option("psf-px", c.psf_sigma_px);
    camera_option("vignetting", c.vignetting);
    camera_option("full-well-e", c.full_well_e);
    camera_option("read-noise-e", c.read_noise_e);
    camera_option("flicker", c.flicker_amplitude);
    if (vm.count("imu-errors")) {
      const std::string v = vm["imu-errors"].as<std::string>();
      if (v != "euroc" && v != "none")
        throw ovton::core::UsageError("--imu-errors must be euroc or none");
      o.imu_errors = v == "euroc" ? ovton::sim::euroc_v1_01_imu_errors() : ovton::sim::ImuErrorModel{};
      modified = true;
    }
    if (vm.count("imu-errors-drop")) {
      ovton::sim::drop_imu_error_parts(o.imu_errors, vm["imu-errors-drop"].as<std::string>());
      modified = true;
    }
    if (vm.count("imu-declare")) {
      const std::string v = vm["imu-declare"].as<std::string>();
      if (v != "fitted" && v != "datasheet")
        throw ovton::core::UsageError("--imu-declare must be fitted or datasheet");
      o.declare_imu_errors = v == "fitted";
      modified = true;
    }
    if (!o.texture_from.empty() && o.scene.texture.style != ovton::sim::TextureStyle::Room)
      throw ovton::core::UsageError("--texture-from needs the room texture (--realism euroc, or --texture room)");
    if (modified || !o.texture_from.empty())
      o.realism += " (modified)";
  }
  o.features_only = vm.count("features-only") > 0;
  o.overwrite = vm.count("force") > 0;
  o.no_images = vm.count("no-images") > 0;
  o.imu_noise = o.imu_bias_walk = vm.count("no-imu-noise") == 0;
  o.td.kind = ovton::sim::parse_td_model(td_model);
  o.td.td0_s = td0_ms * 1e-3;
  o.cam1_own_clock = vm.count("cam1-td-ms") > 0 || vm.count("cam1-td-bias-ms-per-s") > 0;
  o.cam1_td0_s = vm.count("cam1-td-ms") ? vm["cam1-td-ms"].as<double>() * 1e-3 : o.td.td0_s;
  o.cam1_td_bias_s_per_s = vm.count("cam1-td-bias-ms-per-s") ? vm["cam1-td-bias-ms-per-s"].as<double>() * 1e-3 : 0.0;
  o.td.bias_s_per_s = td_bias * 1e-3;
  o.td.noise_s_per_sqrt_s = td_noise * 1e-3;
  o.td.wander_amplitude_s = td_wander_ms * 1e-3;
  o.td.wander_period_s = td_wander_period_s;
  o.gyro_M =
      scale_misalignment(parse_xyz(gyro_axes, "gyro-scale-axes-pct"), parse_xyz(gyro_mis, "gyro-misalignment-mrad"));
  o.accel_M = scale_misalignment(parse_xyz(accel_axes, "accel-scale-axes-pct"),
                                 parse_xyz(accel_mis, "accel-misalignment-mrad"));
  o.extrinsic_rot = parse_xyz(ext_rot, "extrinsic-rot-deg") * M_PI / 180.0;
  o.extrinsic_trans = parse_xyz(ext_trans, "extrinsic-trans-mm") * 1e-3;
  o.readout_s = readout_ms * 1e-3;
  o.focal_error = focal_error_pct * 1e-2;
  o.gyro_scale = gyro_scale_pct * 1e-2;
  if (!cam_yaml.empty()) {
    o.cam = ovton::core::load_euroc_camera_yaml(cam_yaml);
    o.cam_source = cam_yaml;
  }
  if (!imu_yaml.empty()) {
    o.imu = ovton::core::load_euroc_imu_yaml(imu_yaml);
    o.imu_source = imu_yaml;
  }

  ProgressPrinter progress(vm.count("quiet") > 0);
  if (!bench) {
    o.out_dir = out;
    const auto rep = ovton::sim::write_simulation(o, std::ref(progress));
    std::cout << "wrote " << out << ": " << rep.n_images << " frames, " << rep.n_imu << " IMU readings"
              << (o.features_only ? ", " + std::to_string(rep.n_observations) + " feature observations" : "")
              << " along " << rep.trajectory << " in " << rep.total_seconds << " s\n";
    return 0;
  }

  // Benchmark: a real run of bench_frames frames, timed, then sized.
  const bool tmp = out.empty();
  o.out_dir = tmp ? (fs::temp_directory_path() / ("ovton_sim_bench_" + std::to_string(o.seed))).string() : out;
  if (tmp)
    o.overwrite = true;
  o.duration_s = o.first_image_s + (bench_frames - 0.5) / o.cam.rate_hz;
  const auto rep = ovton::sim::write_simulation(o, std::ref(progress));
  const auto sizes = sizes_by_part(fs::path(o.out_dir) / "mav0");
  const double minutes = o.duration_s / 60.0;
  uintmax_t total = 0;
  std::printf("render      %zu frames %dx%d (%s, %.1f renderings per frame for motion blur): %.2f s CPU, %.1f "
              "frames/s on one core (%.1f x real time at %.0f Hz); wall %.2f s, %.1f frames/s at this machine's load\n",
              rep.n_images, o.cam.width, o.cam.height, o.realism.c_str(),
              static_cast<double>(rep.n_renderings) / std::max<size_t>(1, rep.n_images), rep.render_cpu_seconds,
              rep.n_images / rep.render_cpu_seconds, rep.n_images / rep.render_cpu_seconds / o.cam.rate_hz,
              o.cam.rate_hz, rep.render_seconds, rep.n_images / rep.render_seconds);
  std::printf("end to end  %.2f s including scene build, IMU, PNG encoding and disk (%.1f frames/s)\n",
              rep.total_seconds, rep.n_images / rep.total_seconds);
  std::printf("disk per minute of data:\n");
  for (const auto &[part, bytes] : sizes) {
    std::printf("  %-28s %9.2f MB/min\n", part.c_str(), bytes / minutes / 1e6);
    total += bytes;
  }
  std::printf("  %-28s %9.2f MB/min\n", "total", total / minutes / 1e6);
  if (tmp)
    fs::remove_all(o.out_dir);
  return 0;
}

} // namespace ovton::cli
