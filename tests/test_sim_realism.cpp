// The camera effects of `simulate --realism euroc` (ov_sim/camera_effects.h) and its room texture: motion blur is
// centred on the image's stamp (the middle of the exposure) and grows with motion, auto-exposure settles on its
// target, the noise has the variance the sensor model says, vignetting darkens the corners by what was asked,
// flicker averages as it should, the room is mostly plain, and a preset rendering is reproducible byte for byte.
#include "ov_core/cam/camera_model.h"
#include "ov_eval/trackstats.h"
#include "ov_sim/camera_effects.h"
#include "ov_sim/euroc_calib.h"
#include "ov_sim/realism.h"
#include "ov_sim/renderer.h"
#include "ov_sim/simulator.h"
#include "sim_test_util.h"
#include "test_util.h"

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>
#include <opencv2/imgproc.hpp>

using namespace ovton::core;
using namespace ovton::sim;

namespace {

/// A view of the marker room rotating about the camera's y axis at `rate` rad/s, for t seconds from the middle.
FramePose pose_at(double rate, double t) {
  FramePose fp;
  fp.R_WC = ovtest::look_along_x() * Eigen::AngleAxisd(rate * t, Eigen::Vector3d::UnitY()).toRotationMatrix();
  fp.p_WC = Eigen::Vector3d(0.2, -0.1, 1.5);
  return fp;
}

/// Exposure-averaged radiance over [-T/2, T/2] with n sub-frame poses, as the simulator integrates it.
cv::Mat exposed(const Renderer &r, const CameraModel &cam, double rate, double T, int n) {
  cv::Mat acc(cam.height(), cam.width(), CV_32F, cv::Scalar(0));
  for (int j = 0; j < n; ++j)
    r.accumulate(pose_at(rate, ((j + 0.5) / n - 0.5) * T), 1.0f / n, acc);
  return acc;
}

cv::Mat to8(const cv::Mat &f) {
  cv::Mat o;
  f.convertTo(o, CV_8U);
  return o;
}

CameraEffectsOptions effects_on() {
  CameraEffectsOptions c;
  c.enabled = true;
  return c;
}

} // namespace

TEST(SimRealism, MotionBlurIsCentredOnTheStampAndGrowsWithMotion) {
  Scene scene = ovtest::marker_room();
  CameraModel cam(euroc_cam0_calib());
  const Eigen::Vector3d c = scene.plant_marker(Scene::face_index(-1, 0, true), 3.0, 1.5, 0.04);
  const Renderer rend(cam, scene, ovtest::noise_free_rendering());
  Eigen::Vector2d uv;
  const FramePose mid = pose_at(1.0, 0.0);
  ASSERT_TRUE(cam.project(mid.R_WC.transpose() * (c - mid.p_WC), uv));
  const double T = 0.008;
  const cv::Mat sharp = to8(exposed(rend, cam, 1.0, 0.0, 1));
  // 1 rad/s over 8 ms sweeps the image by ~3.7 px; 2 rad/s by ~7 px.
  const cv::Mat blur1 = to8(exposed(rend, cam, 1.0, T, 16)), blur2 = to8(exposed(rend, cam, 2.0, T, 24));
  for (const cv::Mat *img : {&blur1, &blur2}) {
    const Eigen::Vector2d got = ovtest::dark_centroid(*img, uv, 12.0);
    std::cout << "[ measured ] blurred marker centroid off the middle pose's projection by " << (got - uv).norm()
              << " px\n";
    EXPECT_LT((got - uv).norm(), 0.3);
  }
  // The motion is horizontal: horizontal gradients fade as the smear grows.
  const auto mean_abs_gx = [](const cv::Mat &img) {
    cv::Mat gx;
    cv::Sobel(img, gx, CV_32F, 1, 0, 3);
    return cv::mean(cv::abs(gx))[0];
  };
  const double g0 = mean_abs_gx(sharp), g1 = mean_abs_gx(blur1), g2 = mean_abs_gx(blur2);
  std::cout << "[ measured ] mean |Sobel x|: still " << g0 << ", 1 rad/s " << g1 << ", 2 rad/s " << g2 << "\n";
  EXPECT_LT(g1, 0.9 * g0);
  EXPECT_LT(g2, 0.9 * g1);
}

TEST(SimRealism, AutoExposureSettlesOnItsTargetAndFollowsTheScene) {
  CameraModel cam(euroc_cam0_calib());
  CameraEffectsOptions o = effects_on();
  o.vignetting = 0.0;
  o.psf_sigma_px = 0.0;
  CameraEffects fx(o, cam, 1);
  cv::Mat rad(cam.height(), cam.width(), CV_32F, cv::Scalar(60.0f)), img;
  fx.settle(rad);
  fx.develop(rad, 0, 0.0, 0, img);
  EXPECT_NEAR(cv::mean(img)[0], o.ae_target, 1.0);
  // The room gets twice as bright: the next frames darken it back, exposure shrinking, with a lag.
  const double e0 = fx.next_exposure().exposure_s;
  rad *= 2.0;
  fx.develop(rad, 0, 0.0, 1, img);
  const double first = cv::mean(img)[0];
  for (int k = 2; k < 12; ++k)
    fx.develop(rad, 0, 0.0, k, img);
  std::cout << "[ measured ] brighter scene: first frame mean " << first << ", after 10 frames " << cv::mean(img)[0]
            << ", exposure " << e0 * 1e3 << " -> " << fx.next_exposure().exposure_s * 1e3 << " ms\n";
  EXPECT_GT(first, 1.6 * o.ae_target);
  EXPECT_NEAR(cv::mean(img)[0], o.ae_target, 3.0);
  EXPECT_NEAR(fx.next_exposure().exposure_s, e0 / 2, 0.05 * e0);
  // Too dark for the longest exposure: the gain makes up the rest.
  rad.setTo(1.0f);
  for (int k = 12; k < 40; ++k)
    fx.develop(rad, 0, 0.0, k, img);
  EXPECT_DOUBLE_EQ(fx.next_exposure().exposure_s, o.ae_max_exposure_s);
  EXPECT_GT(fx.next_exposure().gain, 1.0);
}

TEST(SimRealism, SensorNoiseVignettingAndFlickerAreWhatTheModelSays) {
  CameraModel cam(euroc_cam0_calib());
  CameraEffectsOptions o = effects_on();
  o.auto_exposure = false;
  o.exposure_s = o.scene_exposure_s; // radiance g develops to g at the centre
  o.psf_sigma_px = 0.0;
  cv::Mat rad(cam.height(), cam.width(), CV_32F, cv::Scalar(100.0f)), img;
  {
    o.vignetting = 0.0;
    CameraEffects fx(o, cam, 2);
    fx.develop(rad, 0, 0.0, 0, img);
    cv::Scalar mean, sd;
    cv::meanStdDev(img, mean, sd);
    // Shot noise of 100/255 of the full well plus read noise, in grey levels; rounding adds 1/12.
    const double e = 100.0 / 255.0 * o.full_well_e;
    const double expect =
        std::sqrt((e + o.read_noise_e * o.read_noise_e) * std::pow(255.0 / o.full_well_e, 2) + 1.0 / 12);
    std::cout << "[ measured ] flat 100: mean " << mean[0] << ", sigma " << sd[0] << " (model " << expect << ")\n";
    EXPECT_NEAR(mean[0], 100.0, 0.1);
    EXPECT_NEAR(sd[0], expect, 0.05 * expect);
  }
  {
    o.vignetting = 0.3;
    o.full_well_e = 1e9; // noise-free
    o.read_noise_e = 0.0;
    CameraEffects fx(o, cam, 2);
    fx.develop(rad, 0, 0.0, 0, img);
    const double centre = img.at<uint8_t>(static_cast<int>(cam.cv()), static_cast<int>(cam.cu()));
    const double corner =
        std::min({img.at<uint8_t>(0, 0), img.at<uint8_t>(0, cam.width() - 1), img.at<uint8_t>(cam.height() - 1, 0),
                  img.at<uint8_t>(cam.height() - 1, cam.width() - 1)});
    EXPECT_NEAR(centre, 100.0, 0.5);
    EXPECT_NEAR(corner, 70.0, 1.0); // the farthest corner loses `vignetting`
  }
  {
    o.vignetting = 0.0;
    o.flicker_amplitude = 0.2;
    o.exposure_s = 0.001;
    CameraEffects fx(o, cam, 2);
    // At the crest of a 100 Hz flicker (t = 2.5 ms) a 1 ms exposure sees 1 + 0.2 sinc-averaged = 1.1935.
    fx.develop(rad * (o.scene_exposure_s / o.exposure_s), 2500000, 0.0, 0, img);
    const double expect = 100.0 * (1.0 + 0.2 * std::sin(M_PI * 0.1) / (M_PI * 0.1));
    EXPECT_NEAR(cv::mean(img)[0], expect, 0.6);
    o.exposure_s = 0.01; // a whole period: no flicker
    CameraEffects fx2(o, cam, 2);
    fx2.develop(rad * (o.scene_exposure_s / o.exposure_s), 2500000, 0.0, 0, img);
    EXPECT_NEAR(cv::mean(img)[0], 100.0, 0.6);
  }
  o = effects_on();
  o.vignetting = 1.0;
  EXPECT_THROW(CameraEffects(o, cam, 0), UsageError);
}

TEST(SimRealism, RoomTextureIsMostlyPlainBlotchesAreNot) {
  SimOptions o;
  o.duration_s = 1.0;
  const auto traj = make_trajectory(o);
  CameraModel cam(o.cam);
  double share[2];
  for (int style = 0; style < 2; ++style) {
    apply_realism(style == 0 ? "clean" : "euroc", o);
    const Scene scene = make_scene(*traj, o);
    const Renderer rend(cam, scene, o.render);
    double sum = 0.0;
    for (int k = 0; k < 4; ++k) {
      cv::Mat acc(cam.height(), cam.width(), CV_32F, cv::Scalar(0)), img;
      rend.accumulate(frame_pose(*traj, o, traj->t_begin_ns() + k * 200000000LL), 1.0f, acc);
      acc.convertTo(img, CV_8U);
      sum += ovton::eval::gradient_stats(img).low_share;
    }
    share[style] = sum / 4;
  }
  std::cout << "[ measured ] built-in flight, plain pixels (Sobel < 20, noise-free): blotches " << share[0] << ", room "
            << share[1] << "\n";
  EXPECT_LT(share[0], 0.35);
  EXPECT_GT(share[1], 0.45);
}

// The same seed gives the same bytes under every compiler, not only run to run: CI builds with gcc (Release) and clang
// (ASan), and the measured tables in docs/ name folders made by gcc. Draws passed as two arguments of one call (or as
// two operands of one operator) are unsequenced, and clang drew them in the other order than gcc: other landmarks,
// other noise, another room (found in session 29 by a test that read 18.5 ms under clang for gcc's 19.8). The golden
// hashes are gcc's; a deliberate change of what the simulator writes updates them (and re-measures what docs/ name).
TEST(SimRealism, EveryCompilerWritesTheSameBytes) {
  const auto fnv = [](const std::string &dir) {
    std::map<std::string, std::string> files;
    for (const auto &e : std::filesystem::recursive_directory_iterator(dir))
      if (e.is_regular_file() && e.path().filename() != "sim.yaml") // sim.yaml names the output folder
        files[std::filesystem::relative(e.path(), dir).string()] = ovtest::read_text(e.path().string());
    uint64_t h = 1469598103934665603ULL; // FNV-1a over names and bytes in name order
    for (const auto &[name, bytes] : files)
      for (const std::string *s : {&name, &bytes})
        for (unsigned char ch : *s)
          h = (h ^ ch) * 1099511628211ULL;
    return h;
  };
  ovtest::TempDir dir;
  SimOptions o;
  apply_realism("euroc", o);
  o.duration_s = 0.3;
  o.agility = 1.0;
  o.out_dir = dir / "euroc";
  write_simulation(o);
  SimOptions f;
  f.features_only = true;
  f.agility = 1.0;
  f.duration_s = 2.0;
  f.out_dir = dir / "features";
  write_simulation(f);
  EXPECT_EQ(fnv(o.out_dir), 0xdee8c949cff2cf76ULL) << std::hex << "euroc render: " << fnv(o.out_dir);
  EXPECT_EQ(fnv(f.out_dir), 0x7b5c91df69fdef69ULL) << std::hex << "feature-level: " << fnv(f.out_dir);
}

TEST(SimRealism, EurocPresetIsReproducibleAndRecordsItsParameters) {
  ovtest::TempDir dir;
  SimOptions o;
  apply_realism("euroc", o);
  o.duration_s = 0.4;
  o.agility = 1.0; // fast enough for several sub-frame renderings per image
  std::map<std::string, std::string> runs[2];
  for (int i = 0; i < 2; ++i) {
    o.out_dir = dir / ("run" + std::to_string(i));
    const SimReport rep = write_simulation(o);
    EXPECT_GT(rep.n_renderings, rep.n_images); // motion blur rendered sub-frames
    for (const auto &e : std::filesystem::recursive_directory_iterator(o.out_dir))
      if (e.is_regular_file())
        runs[i][std::filesystem::relative(e.path(), o.out_dir).string()] = ovtest::read_text(e.path().string());
  }
  ASSERT_EQ(runs[0].size(), runs[1].size());
  for (const auto &[name, bytes] : runs[0])
    EXPECT_TRUE(bytes == runs[1].at(name)) << name << " differs between two runs with the same seed";
  const std::string yaml = runs[0].at("sim.yaml");
  for (const char *key : {"realism: euroc", "texture: room", "auto_exposure: true", "psf_sigma_px", "full_well_e",
                          "vignetting", "flight_spectrum", "stamp_convention"})
    EXPECT_NE(yaml.find(key), std::string::npos) << key << " missing from sim.yaml";
  EXPECT_NE(runs[0].find("mav0/cam0/exposure.csv"), runs[0].end());
  EXPECT_THROW(apply_realism("glossy", o), UsageError);
}
