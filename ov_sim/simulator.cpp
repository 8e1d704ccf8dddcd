#include "ov_sim/simulator.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/types/errors.h"
#include "ov_sim/euroc_calib.h"
#include "ov_sim/random.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

namespace fs = std::filesystem;

namespace ov_sim {

namespace {

// Independent random streams per component: changing e.g. the scene never changes the IMU noise.
enum Stream : uint64_t { kImu = 1, kTd = 2, kScene = 3, kFeatures = 4, kRenderNoise = 5 };

std::ofstream open_out(const fs::path &p) {
  fs::create_directories(p.parent_path());
  std::ofstream f(p, std::ios::binary);
  if (!f)
    throw ov_core::DataError(p.string(), "cannot open for writing");
  return f;
}

void write_text(const fs::path &p, const std::string &text) {
  auto f = open_out(p);
  f << text;
  if (!f)
    throw ov_core::DataError(p.string(), "write failed");
}

std::vector<int64_t> image_times(const Trajectory &traj, const SimOptions &opt) {
  const double rate = opt.cam.rate_hz > 0 ? opt.cam.rate_hz : 20.0;
  const int64_t first = traj.t_begin_ns() + ov_core::s_to_ns(opt.first_image_s);
  std::vector<int64_t> t;
  for (int64_t k = 0;; ++k) {
    const int64_t tk = first + std::llround(k * 1e9 / rate);
    if (tk + ov_core::s_to_ns(opt.readout_s) >
        traj.t_end_ns()) // a rolling shutter's last row, too, lies on the trajectory
      break;
    t.push_back(tk);
  }
  return t;
}

} // namespace

SimOptions::SimOptions() : cam(euroc_cam0_calib()), imu(euroc_imu0_calib()) {}

std::unique_ptr<Trajectory> make_trajectory(const SimOptions &opt) {
  if (!(opt.duration_s > 0.0))
    throw ov_core::UsageError("duration must be positive");
  if (opt.gt_file.empty())
    return std::make_unique<LissajousTrajectory>(opt.duration_s, LissajousTrajectory::kDefaultBeginNs, opt.agility);
  const std::vector<ov_core::StateSample> gt = ov_core::read_trajectory(opt.gt_file);
  if (gt.empty())
    throw ov_core::DataError(opt.gt_file, "no poses");
  const int64_t t0 = gt.front().t_ns + ov_core::s_to_ns(opt.start_s);
  return std::make_unique<SplineTrajectory>(gt, t0, t0 + ov_core::s_to_ns(opt.duration_s), opt.knot_dt_s,
                                            "fit:" + opt.gt_file);
}

ov_core::CameraCalib true_camera(const SimOptions &opt) {
  ov_core::CameraCalib c = opt.cam;
  c.intrinsics.head<2>() *= 1.0 + opt.focal_error;
  return c;
}

int64_t row_time_ns(int64_t t_imu_ns, double row, int height, double readout_s) {
  return t_imu_ns + std::llround(row / height * readout_s * 1e9);
}

FramePose frame_pose(const Trajectory &traj, const SimOptions &opt, int64_t t_imu_ns) {
  FramePose fp;
  camera_pose(traj.sample(t_imu_ns), opt.cam.T_BC, fp.R_WC, fp.p_WC);
  if (opt.readout_s > 0.0) {
    const Eigen::Matrix4d T_BC = opt.cam.T_BC;
    const int height = opt.cam.height;
    const double readout = opt.readout_s;
    fp.at_row = [&traj, T_BC, height, readout, t_imu_ns](double row, Eigen::Matrix3d &R_WC, Eigen::Vector3d &p_WC) {
      camera_pose(traj.sample(row_time_ns(t_imu_ns, row, height, readout)), T_BC, R_WC, p_WC);
    };
  }
  return fp;
}

void camera_pose(const TrajectorySample &s, const Eigen::Matrix4d &T_BC, Eigen::Matrix3d &R_WC, Eigen::Vector3d &p_WC) {
  const Eigen::Matrix3d R_WB = s.q_WB.toRotationMatrix();
  R_WC = R_WB * T_BC.block<3, 3>(0, 0);
  p_WC = s.p_W + R_WB * T_BC.block<3, 1>(0, 3);
}

Scene make_scene(const Trajectory &traj, const SimOptions &opt) {
  std::vector<Eigen::Vector3d> path;
  for (int64_t t = traj.t_begin_ns(); t <= traj.t_end_ns(); t += 50000000)
    path.push_back(traj.sample(t).p_W);
  SceneOptions so = opt.scene;
  so.seed = derive_seed(opt.seed, kScene);
  return Scene::around_path(path, so);
}

std::string sim_yaml(const SimOptions &opt, const Trajectory &traj) {
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
  e << YAML::Key << "t_begin_ns" << YAML::Value << traj.t_begin_ns();
  e << YAML::Key << "t_end_ns" << YAML::Value << traj.t_end_ns();
  e << YAML::EndMap;
  e << YAML::Key << "imu" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "source" << YAML::Value << (opt.imu_from.empty() ? "synthetic" : "real:" + opt.imu_from);
  e << YAML::Key << "calibration" << YAML::Value << opt.imu_source;
  e << YAML::Key << "rate_hz" << YAML::Value << opt.imu.rate_hz;
  e << YAML::Key << "gyroscope_noise_density" << YAML::Value << opt.imu.gyro_noise_density;
  e << YAML::Key << "gyroscope_random_walk" << YAML::Value << opt.imu.gyro_random_walk;
  e << YAML::Key << "accelerometer_noise_density" << YAML::Value << opt.imu.accel_noise_density;
  e << YAML::Key << "accelerometer_random_walk" << YAML::Value << opt.imu.accel_random_walk;
  e << YAML::Key << "noise" << YAML::Value << opt.imu_noise;
  e << YAML::Key << "bias_walk" << YAML::Value << opt.imu_bias_walk;
  e << YAML::Key << "gyro_scale_error" << YAML::Value << opt.gyro_scale; // planted: the gyro reads (1 + s)·ω
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
  const ov_core::CameraCalib tc = true_camera(opt);
  e << YAML::Key << "true_intrinsics" << YAML::Value << YAML::Flow
    << std::vector<double>{tc.intrinsics(0), tc.intrinsics(1), tc.intrinsics(2), tc.intrinsics(3)};
  e << YAML::EndMap;
  e << YAML::Key << "time_offset" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "convention" << YAML::Value << "t_imu = t_cam + td";
  e << YAML::Key << "model" << YAML::Value << to_string(opt.td.kind);
  e << YAML::Key << "td0_s" << YAML::Value << opt.td.td0_s;
  e << YAML::Key << "bias_s_per_s" << YAML::Value << opt.td.bias_s_per_s;
  e << YAML::Key << "noise_s_per_sqrt_s" << YAML::Value << opt.td.noise_s_per_sqrt_s;
  e << YAML::EndMap;
  e << YAML::Key << "scene" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "margin_xy_m" << YAML::Value << opt.scene.margin_xy_m;
  e << YAML::Key << "margin_below_m" << YAML::Value << opt.scene.margin_below_m;
  e << YAML::Key << "margin_above_m" << YAML::Value << opt.scene.margin_above_m;
  e << YAML::Key << "num_boxes" << YAML::Value << opt.scene.num_boxes;
  e << YAML::Key << "box_clearance_m" << YAML::Value << opt.scene.box_clearance_m;
  e << YAML::Key << "texel_m" << YAML::Value << opt.scene.texel_m;
  e << YAML::Key << "feature_min_m" << YAML::Value << opt.scene.feature_min_m;
  e << YAML::Key << "feature_max_m" << YAML::Value << opt.scene.feature_max_m;
  e << YAML::Key << "render_noise_sigma" << YAML::Value << opt.render.noise_sigma;
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

SimReport write_simulation(const SimOptions &opt, const SimProgress &progress) {
  if (opt.out_dir.empty())
    throw ov_core::UsageError("no output folder");
  const double frame_s = 1.0 / (opt.cam.rate_hz > 0 ? opt.cam.rate_hz : 20.0);
  if (!(opt.readout_s >= 0.0 && opt.readout_s <= frame_s))
    throw ov_core::UsageError(
        "rolling-shutter readout must lie in [0, one frame interval = " + std::to_string(frame_s) + " s]");
  if (!(std::abs(opt.focal_error) < 0.5))
    throw ov_core::UsageError("focal error must lie in (-0.5, 0.5) (relative)");
  if (!(std::abs(opt.gyro_scale) < 0.5))
    throw ov_core::UsageError("gyro scale error must lie in (-0.5, 0.5) (relative)");
  if (opt.gyro_scale != 0.0 && !opt.imu_from.empty())
    throw ov_core::UsageError("a gyro scale error is planted in the synthetic IMU, not in a copied one (--imu-from)");
  const auto wall0 = std::chrono::steady_clock::now();
  SimReport rep;
  const std::unique_ptr<Trajectory> traj = make_trajectory(opt);
  rep.trajectory = traj->describe();
  const fs::path mav0 = fs::path(opt.out_dir) / "mav0";
  if (fs::exists(mav0)) {
    if (!opt.overwrite)
      throw ov_core::UsageError("" + mav0.string() + " already exists (use --force to replace it)");
    fs::remove_all(mav0);
  }
  fs::create_directories(mav0);

  write_text(fs::path(opt.out_dir) / "sim.yaml", sim_yaml(opt, *traj));
  write_text(mav0 / "cam0" / "sensor.yaml", euroc_camera_yaml(opt.cam, "simulated cam0 (" + opt.cam_source + ")"));
  write_text(mav0 / "imu0" / "sensor.yaml", euroc_imu_yaml(opt.imu, "simulated imu0 (" + opt.imu_source + ")"));

  // IMU and ground truth (IMU clock).
  ImuSynthOptions io;
  io.calib = opt.imu;
  io.add_noise = opt.imu_noise;
  io.add_bias_walk = opt.imu_bias_walk;
  io.gyro_scale = opt.gyro_scale;
  io.seed = derive_seed(opt.seed, kImu);
  ImuSynthResult imu = synthesize_imu(*traj, io);
  if (!opt.imu_from.empty()) {
    ov_core::LoadOptions lo;
    lo.check_images_exist = false;
    const ov_core::Dataset real = ov_core::load_dataset(opt.imu_from, lo);
    std::vector<ov_core::ImuData> cut;
    for (const auto &m : real.imu)
      if (m.t_imu_ns >= traj->t_begin_ns() && m.t_imu_ns <= traj->t_end_ns())
        cut.push_back(m);
    if (cut.empty() || cut.front().t_imu_ns > traj->t_begin_ns() + 50000000 ||
        cut.back().t_imu_ns < traj->t_end_ns() - 50000000)
      throw ov_core::UsageError("the IMU log of " + opt.imu_from +
                                " does not cover the simulated time span (use the ground truth of the same sequence)");
    imu.imu = cut;
    // Ground-truth biases of a real IMU are only known where the ground truth carries them (17-column csv).
    for (auto &s : imu.truth)
      s.bg.setZero(), s.ba.setZero();
    if (real.has_groundtruth() && real.groundtruth.front().has_velocity) {
      const auto &g = real.groundtruth;
      for (auto &s : imu.truth) {
        auto it = std::lower_bound(g.begin(), g.end(), s.t_ns,
                                   [](const ov_core::StateSample &a, int64_t t) { return a.t_ns < t; });
        if (it == g.end())
          --it;
        s.bg = it->bg;
        s.ba = it->ba;
      }
    }
  }
  rep.n_imu = imu.imu.size();
  {
    auto f = open_out(mav0 / "imu0" / "data.csv");
    f << "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
         "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
    char buf[256];
    for (const auto &m : imu.imu) {
      std::snprintf(buf, sizeof(buf), "%lld,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n", static_cast<long long>(m.t_imu_ns),
                    m.wm.x(), m.wm.y(), m.wm.z(), m.am.x(), m.am.y(), m.am.z());
      f << buf;
    }
    if (!f)
      throw ov_core::DataError((mav0 / "imu0" / "data.csv").string(), "write failed");
  }
  fs::create_directories(mav0 / "state_groundtruth_estimate0");
  ov_core::write_euroc_groundtruth((mav0 / "state_groundtruth_estimate0" / "data.csv").string(), imu.truth);

  // Image instants (IMU clock) and their camera-clock stamps.
  TdModelOptions tdo = opt.td;
  tdo.seed = derive_seed(opt.seed, kTd);
  const std::vector<TimedImage> frames = apply_td_model(image_times(*traj, opt), tdo);
  {
    std::vector<ov_core::TdSample> td;
    for (const auto &f : frames)
      td.push_back(ov_core::TdSample{f.t_cam_ns, f.td_s()});
    fs::create_directories(mav0 / "td_truth");
    ov_core::write_td_truth((mav0 / "td_truth" / "data.csv").string(), td);
  }
  rep.n_images = frames.size();

  // Images (or features), listed in cam0/data.csv as they are written.
  fs::create_directories(mav0 / "cam0" / "data");
  auto list = open_out(mav0 / "cam0" / "data.csv");
  list << "#timestamp [ns],filename\n";
  const bool render = !opt.no_images && !opt.features_only;
  std::unique_ptr<Scene> scene;
  std::unique_ptr<ov_core::CameraModel> cam;
  std::unique_ptr<Renderer> renderer;
  std::unique_ptr<FeatureSimulator> feats;
  std::ofstream feat_out;
  if (render || opt.features_only) {
    if (progress)
      progress("building scene", 0, frames.size());
    scene = std::make_unique<Scene>(make_scene(*traj, opt));
    cam = std::make_unique<ov_core::CameraModel>(true_camera(opt)); // sensor.yaml above keeps opt.cam
  }
  if (render)
    renderer = std::make_unique<Renderer>(*cam, *scene, opt.render);
  if (opt.features_only) {
    FeatureSimOptions fo = opt.features;
    fo.seed = derive_seed(opt.seed, kFeatures);
    feats = std::make_unique<FeatureSimulator>(*cam, *scene, fo);
    feat_out = open_out(mav0 / "cam0" / "features.csv");
    feat_out << "#timestamp_ns,feature_id,u,v\n";
  }
  const std::vector<int> png_params = {cv::IMWRITE_PNG_COMPRESSION, 3};
  cv::Mat img;
  for (size_t k = 0; k < frames.size(); ++k) {
    const TimedImage &fr = frames[k];
    const std::string name = std::to_string(fr.t_cam_ns) + ".png";
    const FramePose pose = frame_pose(*traj, opt, fr.t_imu_ns);
    if (render) {
      const auto r0 = std::chrono::steady_clock::now();
      renderer->render(pose, derive_seed(opt.seed, kRenderNoise) + k, img);
      rep.render_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - r0).count();
      const fs::path file = mav0 / "cam0" / "data" / name;
      if (!cv::imwrite(file.string(), img, png_params))
        throw ov_core::DataError(file.string(), "cannot write image");
    }
    if (feats) {
      char buf[128];
      for (const auto &o : feats->step(pose, fr.t_cam_ns)) {
        std::snprintf(buf, sizeof(buf), "%lld,%llu,%.4f,%.4f\n", static_cast<long long>(o.t_cam_ns),
                      static_cast<unsigned long long>(o.feature_id), o.uv.x(), o.uv.y());
        feat_out << buf;
        ++rep.n_observations;
      }
      feat_out.flush();
    }
    list << fr.t_cam_ns << "," << name << "\n";
    list.flush();
    if (progress)
      progress(render ? "rendering" : "writing", k + 1, frames.size());
  }
  if (!list)
    throw ov_core::DataError((mav0 / "cam0" / "data.csv").string(), "write failed");
  rep.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return rep;
}

} // namespace ov_sim
