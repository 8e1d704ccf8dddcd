#include "ov_sim/simulator.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_codecs.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/math/so3.h"
#include "ov_core/types/errors.h"
#include "ov_sim/euroc_calib.h"
#include "ov_sim/gt_alignment.h"
#include "ov_sim/random.h"
#include "ov_sim/real_imu.h"
#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <optional>

namespace fs = std::filesystem;

namespace ovton::sim {

namespace {

// Independent random streams per component: changing e.g. the scene never changes the IMU noise.
enum Stream : uint64_t {
  kImu = 1,
  kTd = 2,
  kScene = 3,
  kFeatures = 4,
  kRenderNoise = 5,
  kImuErrors = 6,
  kRenderNoiseCam1 = 7
};

std::ofstream open_out(const fs::path &p) {
  fs::create_directories(p.parent_path());
  std::ofstream f(p, std::ios::binary);
  if (!f)
    throw ovton::core::DataError(p.string(), "cannot open for writing");
  return f;
}

void write_text(const fs::path &p, const std::string &text) {
  auto f = open_out(p);
  f << text;
  if (!f)
    throw ovton::core::DataError(p.string(), "write failed");
}

/// CPU time of the calling thread [s] (the renderer runs on one thread: its cost on one core, whatever the load).
double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// Longest exposure a frame can get: the shutter is open for half of it after the frame's instant.
double max_exposure_s(const SimOptions &opt) {
  const CameraEffectsOptions &c = opt.camera_effects;
  if (!c.enabled)
    return 0.0;
  return c.auto_exposure ? c.ae_max_exposure_s : c.exposure_s;
}

std::vector<int64_t> image_times(const Trajectory &traj, const SimOptions &opt) {
  const double rate = opt.cam.rate_hz > 0 ? opt.cam.rate_hz : 20.0;
  const int64_t first = traj.t_begin_ns() + ovton::core::s_to_ns(opt.first_image_s);
  const int64_t half_exposure = ovton::core::s_to_ns(max_exposure_s(opt) / 2);
  if (first - half_exposure < traj.t_begin_ns())
    throw ovton::core::UsageError("the first image's exposure would start before the trajectory");
  std::vector<int64_t> t;
  for (int64_t k = 0;; ++k) {
    const int64_t tk = first + std::llround(k * 1e9 / rate);
    // A rolling shutter's last row, and the end of every exposure, too, lie on the trajectory.
    if (tk + ovton::core::s_to_ns(opt.readout_s) + half_exposure > traj.t_end_ns())
      break;
    t.push_back(tk);
  }
  return t;
}

/// cam1's IMU-clock instants under its own clock (SimOptions::cam1_own_clock), in integer ns so that the truth file's
/// t_cam + td1 is the rendered instant exactly. Frames whose cam1 instant (with its exposure and readout) would leave
/// the trajectory are removed from `frames`.
std::vector<int64_t> cam1_instants(const Trajectory &traj, const SimOptions &opt, std::vector<TimedImage> &frames) {
  const int64_t half_exposure = ovton::core::s_to_ns(max_exposure_s(opt) / 2);
  std::vector<TimedImage> kept;
  std::vector<int64_t> t1;
  const int64_t first = frames.empty() ? 0 : frames.front().t_cam_ns;
  for (const TimedImage &f : frames) {
    const double age_s = ovton::core::ns_to_s(f.t_cam_ns - first);
    const int64_t t = f.t_cam_ns + ovton::core::s_to_ns(opt.cam1_td0_s + opt.cam1_td_bias_s_per_s * age_s);
    if (t - half_exposure < traj.t_begin_ns() ||
        t + ovton::core::s_to_ns(opt.readout_s) + half_exposure > traj.t_end_ns())
      continue;
    kept.push_back(f);
    t1.push_back(t);
  }
  if (kept.empty())
    throw ovton::core::UsageError("cam1's clock puts every image off the trajectory");
  frames = std::move(kept);
  return t1;
}

/// How far the image moves between two poses of the camera [px]: the rotation angle at the focal length, plus the
/// translation seen at 1 m (a conservative room-scale depth for sampling the exposure finely enough).
double image_motion_px(const FramePose &a, const FramePose &b, double focal_px) {
  const Eigen::AngleAxisd d(a.R_WC.transpose() * b.R_WC);
  return focal_px * (std::abs(d.angle()) + (b.p_WC - a.p_WC).norm() / 1.0);
}

/// One image through the camera effects: the scene integrated over the exposure along sub-frame poses (motion
/// blur), then developed (PSF, vignetting, noise, auto-exposure, 8 bits). t_mid_ns is the exposure's middle.
int render_exposed(const Renderer &renderer, CameraEffects &effects, const Trajectory &traj, const SimOptions &opt,
                   int64_t t_mid_ns, uint64_t frame_index, cv::Mat &acc, cv::Mat &img) {
  const double T = effects.next_exposure().exposure_s;
  const int64_t half = ovton::core::s_to_ns(T / 2);
  const double motion = image_motion_px(frame_pose(traj, opt, t_mid_ns - half), frame_pose(traj, opt, t_mid_ns + half),
                                        std::max(opt.cam.intrinsics(0), opt.cam.intrinsics(1)));
  const int n = effects.blur_samples(motion);
  acc.create(opt.cam.height, opt.cam.width, CV_32F);
  acc.setTo(0.0f);
  for (int j = 0; j < n; ++j) {
    // Sample j at the centre of the j-th of n equal slices of the exposure.
    const int64_t t = t_mid_ns + std::llround(((j + 0.5) / n - 0.5) * T * 1e9);
    renderer.accumulate(frame_pose(traj, opt, t), 1.0f / static_cast<float>(n), acc);
  }
  effects.develop(acc, t_mid_ns, opt.readout_s, frame_index, img);
  return n;
}

} // namespace

SimOptions::SimOptions() : cam(euroc_cam0_calib()), cam1(euroc_cam1_calib()), imu(euroc_imu0_calib()) {}

std::unique_ptr<Trajectory> make_trajectory(const SimOptions &opt) {
  if (!(opt.duration_s > 0.0))
    throw ovton::core::UsageError("duration must be positive");
  if (opt.gt_file.empty())
    return std::make_unique<LissajousTrajectory>(opt.duration_s, LissajousTrajectory::kDefaultBeginNs, opt.agility);
  std::vector<ovton::core::StateSample> gt = ovton::core::read_trajectory(opt.gt_file);
  if (gt.empty())
    throw ovton::core::DataError(opt.gt_file, "no poses");
  std::string source = "fit:" + opt.gt_file;
  // --start-s counts from the file's first pose, also when the alignment moves the poses in time.
  int64_t t0 = gt.front().t_ns + ovton::core::s_to_ns(opt.start_s);
  if (!opt.align_gt_to.empty()) {
    if (!(opt.align_blend_hz >= 0.0 && std::isfinite(opt.align_blend_hz)))
      throw ovton::core::UsageError("the ground-truth blend's crossover (--align-blend-hz) must be >= 0 (0: no blend)");
    const RealImu real = load_real_imu(opt.align_gt_to);
    if (opt.align_blend_hz > 0.0 && real.groundtruth.empty())
      throw ovton::core::UsageError(opt.align_gt_to + " has no ground truth to blend " + opt.gt_file +
                                    " with (--align-blend-hz 0: the aligned file alone)");
    const GtAlignment a = align_gt_to_imu(real.imu, gt, real.groundtruth, opt.knot_dt_s);
    gt = apply_gt_alignment(gt, a);
    t0 -= ovton::core::s_to_ns(a.shift_s);
    source += "; " + describe_gt_alignment(a) + " (" + opt.align_gt_to + ")";
    if (opt.align_blend_hz > 0.0) {
      gt = blend_gt(real.groundtruth, gt, opt.align_blend_hz, 0.1);
      char b[96];
      std::snprintf(b, sizeof(b), "; below %g Hz the motion of its ground truth", opt.align_blend_hz);
      source += b;
    }
  }
  return std::make_unique<SplineTrajectory>(gt, t0, t0 + ovton::core::s_to_ns(opt.duration_s), opt.knot_dt_s, source);
}

ovton::core::CameraCalib true_camera(const SimOptions &opt) {
  ovton::core::CameraCalib c = opt.cam;
  c.intrinsics.head<2>() *= 1.0 + opt.focal_error;
  c.T_BC.block<3, 3>(0, 0) = ovton::core::so3_exp(opt.extrinsic_rot) * opt.cam.T_BC.block<3, 3>(0, 0);
  c.T_BC.block<3, 1>(0, 3) += opt.extrinsic_trans;
  return c;
}

int64_t row_time_ns(int64_t t_imu_ns, double row, int height, double readout_s) {
  return t_imu_ns + std::llround(row / height * readout_s * 1e9);
}

FramePose frame_pose(const Trajectory &traj, const SimOptions &opt, int64_t t_imu_ns) {
  FramePose fp;
  const Eigen::Matrix4d T_BC = true_camera(opt).T_BC; // the data's extrinsics (the yaml keeps opt.cam's)
  camera_pose(traj.sample(t_imu_ns), T_BC, fp.R_WC, fp.p_WC);
  if (opt.readout_s > 0.0) {
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
  if (!opt.texture_from.empty() && !so.texture.crops)
    so.texture.crops = std::make_shared<const std::vector<cv::Mat>>(load_texture_crops(opt.texture_from));
  return Scene::around_path(path, so);
}

bool declares_fitted_imu_noise(const SimOptions &opt) {
  return opt.declare_imu_errors && (!opt.imu_from.empty() || (opt.imu_errors.enabled && opt.imu_noise));
}

ovton::core::ImuCalib declared_imu(const SimOptions &opt) {
  if (!declares_fitted_imu_noise(opt))
    return opt.imu;
  // A synthetic log holds the datasheet noise plus the model's coloured noise (add_imu_errors); a filter told only
  // the datasheet is overconfident (docs/consistency_images.md). A real EuRoC log (ADIS16448) is
  // noisier than its datasheet as the model measured on it says: declaring the datasheet made semi-real runs
  // overconfident (NEES 58 / 108 on the real cut's span, APE 6 cm instead of 1).
  return fitted_imu_noise(opt.imu_from.empty() ? opt.imu_errors : euroc_v1_01_imu_errors(), opt.imu);
}

SimReport write_simulation(const SimOptions &opt, const SimProgress &progress) {
  if (opt.out_dir.empty())
    throw ovton::core::UsageError("no output folder");
  const double frame_s = 1.0 / (opt.cam.rate_hz > 0 ? opt.cam.rate_hz : 20.0);
  if (!(opt.readout_s >= 0.0 && opt.readout_s <= frame_s))
    throw ovton::core::UsageError(
        "rolling-shutter readout must lie in [0, one frame interval = " + std::to_string(frame_s) + " s]");
  if (opt.cameras < 1 || opt.cameras > 2 || (opt.cameras == 2 && opt.features_only))
    throw ovton::core::UsageError("cameras must be 1 or 2 (2: rendered images, not --features-only)");
  if (opt.cam1_own_clock &&
      (opt.cameras < 2 || !(std::abs(opt.cam1_td0_s) < 1.0) || !(std::abs(opt.cam1_td_bias_s_per_s) < 0.01)))
    throw ovton::core::UsageError("cam1's own clock needs cameras 2, |offset| < 1 s and |drift| < 10 ms/s");
  if (!(std::abs(opt.focal_error) < 0.5))
    throw ovton::core::UsageError("focal error must lie in (-0.5, 0.5) (relative)");
  if (!(std::abs(opt.gyro_scale) < 0.5))
    throw ovton::core::UsageError("gyro scale error must lie in (-0.5, 0.5) (relative)");
  if ((opt.gyro_scale != 0.0 || !opt.gyro_M.isZero() || !opt.accel_M.isZero()) && !opt.imu_from.empty())
    throw ovton::core::UsageError(
        "IMU scale errors are planted in the synthetic IMU, not in a copied one (--imu-from)");
  if (!(opt.gyro_M.cwiseAbs().maxCoeff() < 0.5 && opt.accel_M.cwiseAbs().maxCoeff() < 0.5))
    throw ovton::core::UsageError("IMU per-axis scale and misalignment must lie in (-0.5, 0.5) (relative)");
  if (!(opt.extrinsic_rot.norm() < 0.5 && opt.extrinsic_trans.norm() < 1.0))
    throw ovton::core::UsageError("extrinsic error: rotation must be below 0.5 rad and translation below 1 m");
  const auto wall0 = std::chrono::steady_clock::now();
  SimReport rep;
  const std::unique_ptr<Trajectory> traj = make_trajectory(opt);
  rep.trajectory = traj->describe();
  const fs::path mav0 = fs::path(opt.out_dir) / "mav0";
  if (fs::exists(mav0)) {
    if (!opt.overwrite)
      throw ovton::core::UsageError("" + mav0.string() + " already exists (use --force to replace it)");
    fs::remove_all(mav0);
  }
  fs::create_directories(mav0);

  std::optional<RealImu> real;
  RealImuBiases real_biases;
  if (!opt.imu_from.empty()) {
    if (opt.gt_file.empty())
      throw ovton::core::UsageError("a real IMU log (imu_from) needs the ground truth of the same flight (gt_file)");
    real = load_real_imu(opt.imu_from);
    real_biases =
        real_imu_biases(*real, ovton::core::read_trajectory(opt.gt_file), "--gt " + opt.gt_file, opt.knot_dt_s);
  }
  write_text(fs::path(opt.out_dir) / "sim.yaml", sim_yaml(opt, *traj, real_biases.source));
  write_text(mav0 / "cam0" / "sensor.yaml", euroc_camera_yaml(opt.cam, "simulated cam0 (" + opt.cam_source + ")"));
  const bool fitted = declares_fitted_imu_noise(opt);
  write_text(mav0 / "imu0" / "sensor.yaml",
             euroc_imu_yaml(declared_imu(opt),
                            (opt.imu_from.empty() ? "simulated imu0 (" + opt.imu_source
                                                  : "real imu0 log of " + opt.imu_from + " (EuRoC ADIS16448") +
                                (fitted ? "; noise fitted to the realistic IMU's Allan variance" : "") + ")"));

  // IMU and ground truth (IMU clock).
  ImuSynthOptions io;
  io.calib = opt.imu;
  io.add_noise = opt.imu_noise;
  io.add_bias_walk = opt.imu_bias_walk;
  io.gyro_scale = opt.gyro_scale;
  io.gyro_M = opt.gyro_M;
  io.accel_M = opt.accel_M;
  io.seed = derive_seed(opt.seed, kImu);
  ImuSynthResult imu = synthesize_imu(*traj, io);
  if (opt.imu_errors.enabled && opt.imu_from.empty())
    add_imu_errors(*traj, opt.imu_errors, opt.imu_noise ? opt.imu.gyro_noise_density : 0.0,
                   opt.imu_noise ? opt.imu.accel_noise_density : 0.0, derive_seed(opt.seed, kImuErrors), imu.imu,
                   imu.truth);
  if (real) {
    std::vector<ovton::core::ImuData> cut;
    for (const auto &m : real->imu)
      if (m.t_imu_ns >= traj->t_begin_ns() && m.t_imu_ns <= traj->t_end_ns())
        cut.push_back(m);
    if (cut.empty() || cut.front().t_imu_ns > traj->t_begin_ns() + 50000000 ||
        cut.back().t_imu_ns < traj->t_end_ns() - 50000000)
      throw ovton::core::UsageError(
          "the IMU log of " + opt.imu_from +
          " does not cover the simulated time span (use the ground truth of the same sequence)");
    imu.imu = cut;
    // A real IMU's biases: what its ground truth, or --gt, says, else measured from the log (real_imu.h).
    for (auto &s : imu.truth)
      real_biases.at(s.t_ns, s.bg, s.ba);
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
      throw ovton::core::DataError((mav0 / "imu0" / "data.csv").string(), "write failed");
  }
  fs::create_directories(mav0 / "state_groundtruth_estimate0");
  ovton::core::write_euroc_groundtruth((mav0 / "state_groundtruth_estimate0" / "data.csv").string(), imu.truth);

  // Image instants (IMU clock) and their camera-clock stamps.
  TdModelOptions tdo = opt.td;
  tdo.seed = derive_seed(opt.seed, kTd);
  std::vector<TimedImage> frames = apply_td_model(image_times(*traj, opt), tdo);
  // cam1's instants (IMU clock) by frame: cam0's, or its own clock's (cam1_own_clock), where frames whose cam1
  // instant leaves the trajectory are dropped for both cameras.
  std::vector<int64_t> t_imu1;
  if (opt.cameras >= 2 && opt.cam1_own_clock)
    t_imu1 = cam1_instants(*traj, opt, frames);
  else
    for (const auto &f : frames)
      t_imu1.push_back(f.t_imu_ns);
  const auto write_truth = [&](const std::string &dir, const auto &td_ns_of) {
    std::vector<ovton::core::TdSample> td;
    for (size_t k = 0; k < frames.size(); ++k)
      td.push_back(ovton::core::TdSample{frames[k].t_cam_ns, 1e-9 * static_cast<double>(td_ns_of(k))});
    fs::create_directories(mav0 / dir);
    ovton::core::write_td_truth((mav0 / dir / "data.csv").string(), td);
  };
  write_truth("td_truth", [&](size_t k) { return frames[k].td_ns; });
  if (opt.cameras >= 2 && opt.cam1_own_clock)
    write_truth("td_truth_cam1", [&](size_t k) { return t_imu1[k] - frames[k].t_cam_ns; });
  rep.n_images = frames.size();

  // Images (or features), listed in cam0/data.csv as they are written.
  fs::create_directories(mav0 / "cam0" / "data");
  auto list = open_out(mav0 / "cam0" / "data.csv");
  list << "#timestamp [ns],filename\n";
  const bool render = !opt.no_images && !opt.features_only;
  std::unique_ptr<Scene> scene;
  std::unique_ptr<ovton::core::CameraModel> cam;
  std::unique_ptr<Renderer> renderer;
  std::unique_ptr<FeatureSimulator> feats;
  std::ofstream feat_out;
  if (render || opt.features_only) {
    if (progress)
      progress("building scene", 0, frames.size());
    scene = std::make_unique<Scene>(make_scene(*traj, opt));
    cam = std::make_unique<ovton::core::CameraModel>(true_camera(opt)); // sensor.yaml above keeps opt.cam
  }
  std::unique_ptr<CameraEffects> effects;
  std::ofstream exposure_out;
  cv::Mat acc; // exposure-averaged radiance
  if (render) {
    renderer = std::make_unique<Renderer>(*cam, *scene, opt.render);
    if (opt.camera_effects.enabled) {
      effects = std::make_unique<CameraEffects>(opt.camera_effects, *cam, derive_seed(opt.seed, kRenderNoise));
      // Not part of the EuRoC layout (readers ignore it): what the camera did, frame by frame.
      exposure_out = open_out(mav0 / "cam0" / "exposure.csv");
      exposure_out << "#timestamp [ns] (camera clock; middle of the exposure),exposure_s,gain,blur_samples\n";
      if (!frames.empty()) {
        acc.create(opt.cam.height, opt.cam.width, CV_32F);
        acc.setTo(0.0f);
        renderer->accumulate(frame_pose(*traj, opt, frames.front().t_imu_ns), 1.0f, acc);
        effects->settle(acc);
      }
    }
  }
  // The second camera of a stereo rig: its own renderer and camera effects (its sensor has its own noise).
  SimOptions opt1 = opt;
  opt1.cam = opt.cam1;
  std::unique_ptr<Renderer> renderer1;
  std::unique_ptr<CameraEffects> effects1;
  std::unique_ptr<ovton::core::CameraModel> cam1;
  std::ofstream list1;
  cv::Mat acc1, img1;
  if (render && opt.cameras >= 2) {
    cam1 = std::make_unique<ovton::core::CameraModel>(true_camera(opt1));
    renderer1 = std::make_unique<Renderer>(*cam1, *scene, opt.render);
    write_text(mav0 / "cam1" / "sensor.yaml", euroc_camera_yaml(opt.cam1, "simulated cam1 (EuRoC stereo pair)"));
    fs::create_directories(mav0 / "cam1" / "data");
    list1 = open_out(mav0 / "cam1" / "data.csv");
    list1 << "#timestamp [ns],filename\n";
    if (opt.camera_effects.enabled) {
      effects1 = std::make_unique<CameraEffects>(opt.camera_effects, *cam1, derive_seed(opt.seed, kRenderNoiseCam1));
      if (!frames.empty()) {
        acc1.create(opt1.cam.height, opt1.cam.width, CV_32F);
        acc1.setTo(0.0f);
        renderer1->accumulate(frame_pose(*traj, opt1, frames.front().t_imu_ns), 1.0f, acc1);
        effects1->settle(acc1);
      }
    }
  }
  if (opt.features_only) {
    FeatureSimOptions fo = opt.features;
    fo.seed = derive_seed(opt.seed, kFeatures);
    feats = std::make_unique<FeatureSimulator>(*cam, *scene, fo);
    feat_out = open_out(mav0 / "cam0" / "features.csv");
    feat_out << "#timestamp_ns,feature_id,u,v\n";
  }
  const std::vector<int> png_params = {ovton::core::png_compression_param(), 3};
  cv::Mat img;
  for (size_t k = 0; k < frames.size(); ++k) {
    const TimedImage &fr = frames[k];
    const std::string name = std::to_string(fr.t_cam_ns) + ".png";
    const FramePose pose = frame_pose(*traj, opt, fr.t_imu_ns);
    if (render) {
      const auto r0 = std::chrono::steady_clock::now();
      const double c0 = thread_cpu_seconds();
      if (effects) {
        const Exposure ex = effects->next_exposure();
        const int n = render_exposed(*renderer, *effects, *traj, opt, fr.t_imu_ns, k, acc, img);
        rep.n_renderings += n;
        char buf[128];
        std::snprintf(buf, sizeof(buf), "%lld,%.9f,%.6f,%d\n", static_cast<long long>(fr.t_cam_ns), ex.exposure_s,
                      ex.gain, n);
        exposure_out << buf;
        exposure_out.flush();
      } else {
        renderer->render(pose, derive_seed(opt.seed, kRenderNoise) + k, img);
        ++rep.n_renderings;
      }
      rep.render_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - r0).count();
      rep.render_cpu_seconds += thread_cpu_seconds() - c0;
      const fs::path file = mav0 / "cam0" / "data" / name;
      if (!ovton::core::write_image(file.string(), img, png_params))
        throw ovton::core::DataError(file.string(), "cannot write image");
    }
    if (renderer1) {
      if (effects1)
        rep.n_renderings += render_exposed(*renderer1, *effects1, *traj, opt1, t_imu1[k], k, acc1, img1);
      else
        renderer1->render(frame_pose(*traj, opt1, t_imu1[k]), derive_seed(opt.seed, kRenderNoiseCam1) + k, img1);
      const fs::path file = mav0 / "cam1" / "data" / name;
      if (!ovton::core::write_image(file.string(), img1, png_params))
        throw ovton::core::DataError(file.string(), "cannot write image");
      list1 << fr.t_cam_ns << "," << name << "\n";
      list1.flush();
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
    throw ovton::core::DataError((mav0 / "cam0" / "data.csv").string(), "write failed");
  rep.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return rep;
}

} // namespace ovton::sim
