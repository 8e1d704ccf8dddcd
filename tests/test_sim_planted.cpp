// Planted camera effects in `simulate`: a rolling-shutter readout (each image row seen from its own instant) and a
// focal-length error (data made with other intrinsics than cam0/sensor.yaml says). The observations and images must
// carry exactly the planted effect, so that `diagnose` tests can hold it to a known size.
#include "ov_core/io/dataset.h"
#include "ov_core/math/so3.h"
#include "ov_core/types/errors.h"
#include "ov_sim/euroc_calib.h"
#include "ov_sim/random.h"
#include "ov_sim/renderer.h"
#include "ov_sim/scene.h"
#include "ov_sim/simulator.h"
#include "sim_test_util.h"
#include "test_util.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <map>

using namespace ovton::core;
using namespace ovton::sim;
using ovtest::median;

namespace {

/// Pose of the camera at IMU time t.
void pose_at(const Trajectory &traj, const SimOptions &o, int64_t t, Eigen::Matrix3d &R_WC, Eigen::Vector3d &p_WC) {
  camera_pose(traj.sample(t), o.cam.T_BC, R_WC, p_WC);
}

} // namespace

TEST(SimPlanted, RollingShutterObservationIsTheProjectionFromItsRowsInstant) {
  SimOptions o;
  o.duration_s = 3.0;
  o.readout_s = 0.030;
  ovtest::NoiseFreeFeatureSim sim(o);
  const auto &traj = sim.traj;
  const CameraModel &cam = sim.cam;
  FeatureSimulator &fsim = sim.features;
  std::vector<double> shift_px, predicted_px;
  long n = 0;
  for (int64_t t = traj->t_begin_ns(); t + s_to_ns(o.readout_s) <= traj->t_end_ns(); t += 50000000) {
    const FramePose pose = frame_pose(*traj, o, t);
    ASSERT_TRUE(static_cast<bool>(pose.at_row));
    for (const auto &ob : fsim.step(pose, t)) {
      const Eigen::Vector3d &P = fsim.landmarks()[fsim.landmark_of(ob.feature_id)];
      // Exact: the landmark projected from the pose at row_time(observed row) lands on the observation.
      Eigen::Matrix3d R_WC;
      Eigen::Vector3d p_WC;
      pose_at(*traj, o, row_time_ns(t, ob.uv.y(), o.cam.height, o.readout_s), R_WC, p_WC);
      Eigen::Vector2d uv;
      ASSERT_TRUE(cam.project(R_WC.transpose() * (P - p_WC), uv));
      EXPECT_LT((uv - ob.uv).norm(), 1e-6);
      ++n;
      // The effect is the image motion over the row's delay: compare with the global-shutter projection and with
      // the image velocity (finite difference over ±1 ms) times v/height·readout.
      Eigen::Vector2d uv0, uv_p, uv_m;
      const auto proj = [&](int64_t ti, Eigen::Vector2d &out) {
        pose_at(*traj, o, ti, R_WC, p_WC);
        return cam.project(R_WC.transpose() * (P - p_WC), out);
      };
      ASSERT_TRUE(proj(t, uv0));
      const double dt = ob.uv.y() / o.cam.height * o.readout_s;
      if (proj(t + s_to_ns(dt) + 1000000, uv_p) && proj(t + s_to_ns(dt) - 1000000, uv_m)) {
        const Eigen::Vector2d V = (uv_p - uv_m) / 0.002;
        shift_px.push_back((ob.uv - uv0).norm());
        predicted_px.push_back((ob.uv - uv0 - V * dt).norm());
      }
    }
  }
  ASSERT_GT(n, 5000);
  std::cout << "[ measured ] " << n << " observations; shift from the row-0 projection: median " << median(shift_px)
            << " px; left after V * (v/height) * readout: median " << median(predicted_px) << " px\n";
  EXPECT_GT(median(shift_px), 0.5);                         // a 30 ms readout moves points visibly
  EXPECT_LT(median(predicted_px), 0.05 * median(shift_px)); // and it is the first-order model diagnose fits
}

TEST(SimPlanted, FocalErrorDataUseTheTrueIntrinsicsAndTheYamlTheNominal) {
  ovtest::TempDir dir;
  SimOptions o;
  o.out_dir = dir.str();
  o.duration_s = 2.0;
  o.seed = 5;
  o.features_only = true;
  o.features.pixel_noise = 0.0;
  o.focal_error = 0.02;
  write_simulation(o);
  const Dataset ds = load_dataset(dir.str());
  // cam0/sensor.yaml keeps the nominal intrinsics; sim.yaml says what the data were made with.
  EXPECT_EQ(ds.cam.intrinsics, o.cam.intrinsics);
  EXPECT_EQ(true_camera(o).intrinsics(0), o.cam.intrinsics(0) * 1.02);
  EXPECT_EQ(true_camera(o).intrinsics.tail<2>(), o.cam.intrinsics.tail<2>());
  EXPECT_NE(ovtest::read_text(dir / "sim.yaml").find("focal_error: 0.02"), std::string::npos);
  // Replay the writer's feature stream with the true camera: the written pixels are its projections.
  const auto traj = make_trajectory(o);
  const Scene scene = make_scene(*traj, o);
  const CameraModel true_cam(true_camera(o)), yaml_cam(ds.cam);
  FeatureSimOptions fo = o.features;
  fo.seed = derive_seed(o.seed, 4); // the writer's feature stream
  FeatureSimulator fsim(true_cam, scene, fo);
  std::vector<double> nominal_px;
  long n = 0;
  for (const auto &im : ds.images) {
    const int64_t t_imu = im.t_cam_ns + s_to_ns(ds.td_truth_at(im.t_cam_ns));
    const FramePose pose = frame_pose(*traj, o, t_imu);
    const auto obs = fsim.step(pose, im.t_cam_ns);
    ASSERT_EQ(obs.size(), im.features->size());
    for (size_t q = 0; q < obs.size(); ++q) {
      ASSERT_EQ(obs[q].feature_id, (*im.features)[q].id);
      EXPECT_LT((obs[q].uv - (*im.features)[q].uv).norm(), 1e-4); // 4 decimals in features.csv
      const Eigen::Vector3d p_C =
          pose.R_WC.transpose() * (fsim.landmarks()[fsim.landmark_of(obs[q].feature_id)] - pose.p_WC);
      Eigen::Vector2d uv_true, uv_yaml;
      ASSERT_TRUE(true_cam.project(p_C, uv_true) && yaml_cam.project(p_C, uv_yaml));
      EXPECT_LT((uv_true - obs[q].uv).norm(), 1e-9);
      nominal_px.push_back((uv_yaml - obs[q].uv).norm());
      ++n;
    }
  }
  ASSERT_GT(n, 3000);
  std::cout << "[ measured ] " << n << " observations; 2 % focal error moves them by a median " << median(nominal_px)
            << " px from the sensor.yaml projection\n";
  EXPECT_GT(median(nominal_px), 2.0);
}

TEST(SimPlanted, RollingShutterRenderDrawsEachRowFromItsPose) {
  Scene scene = ovtest::marker_room();
  CameraModel cam(euroc_cam0_calib());
  const RenderOptions ro = ovtest::noise_free_rendering();
  const Eigen::Matrix3d R_look = ovtest::look_along_x();
  const Eigen::Vector3d p_WC(0.2, -0.1, 1.5);
  // The camera pans about its y axis at 1 rad/s while a 30 ms readout runs down the image: ~13 px over the rows.
  const double readout = 0.030, rate = 1.0;
  FramePose pose;
  pose.R_WC = R_look;
  pose.p_WC = p_WC;
  pose.at_row = [&](double row, Eigen::Matrix3d &R, Eigen::Vector3d &p) {
    R = R_look * Eigen::AngleAxisd(rate * readout * row / cam.height(), Eigen::Vector3d::UnitY()).toRotationMatrix();
    p = p_WC;
  };
  const std::vector<std::pair<double, double>> where = {{2.9, 2.2}, {3.3, 1.5}, {2.6, 0.8}}; // +x wall (u, v) [m]
  std::vector<Eigen::Vector3d> centres;
  for (const auto &[u, v] : where)
    centres.push_back(scene.plant_marker(Scene::face_index(-1, 0, true), u, v, 0.04));
  Renderer rend(cam, scene, ro);
  cv::Mat img;
  rend.render(pose, 0, img);
  for (size_t i = 0; i < centres.size(); ++i) {
    // Where the marker's row sees it: fixed point of row -> pose(row) -> projected row.
    Eigen::Vector2d uv, uv0;
    ASSERT_TRUE(cam.project(R_look.transpose() * (centres[i] - p_WC), uv0));
    uv = uv0;
    for (int it = 0; it < 20; ++it) {
      Eigen::Matrix3d R;
      Eigen::Vector3d p;
      pose.at_row(uv.y(), R, p);
      ASSERT_TRUE(cam.project(R.transpose() * (centres[i] - p), uv));
    }
    ASSERT_TRUE(cam.in_image(uv, 30)) << uv.transpose();
    const double r_px = 0.04 / (R_look.transpose() * (centres[i] - p_WC)).z() * cam.fu();
    const Eigen::Vector2d got = ovtest::dark_centroid(img, uv, 1.5 * r_px);
    std::cout << "[ measured ] marker " << i << ": rolling-shutter projection (" << uv.transpose() << "), drawn "
              << (got - uv).norm() << " px from it, " << (uv - uv0).norm() << " px from the row-0 projection\n";
    EXPECT_GT((uv - uv0).norm(), 3.0);
    EXPECT_LT((got - uv).norm(), 0.35);
  }
}

// A camera-IMU extrinsic error: the data's camera pose uses the moved T_BC, the written sensor.yaml the nominal one.
TEST(SimPlanted, ExtrinsicErrorMovesTheDataCameraNotTheYaml) {
  SimOptions o;
  o.extrinsic_rot = Eigen::Vector3d(0.003, -0.004, 0.005);
  o.extrinsic_trans = Eigen::Vector3d(0.02, -0.01, 0.005);
  const auto traj = make_trajectory(o);
  const int64_t t = traj->t_begin_ns() + 500000000;
  Eigen::Matrix3d R_nom;
  Eigen::Vector3d p_nom;
  camera_pose(traj->sample(t), o.cam.T_BC, R_nom, p_nom);
  const FramePose fp = frame_pose(*traj, o, t);
  const Eigen::Matrix3d R_WB = traj->sample(t).q_WB.toRotationMatrix();
  // R_WC = R_WB·Exp(φ)·R_BC: the camera turned by φ in the body frame; p_WC moved by R_WB·δp.
  EXPECT_LT((R_WB.transpose() * fp.R_WC * R_nom.transpose() * R_WB - so3_exp(o.extrinsic_rot)).norm(), 1e-12);
  EXPECT_LT((R_WB.transpose() * (fp.p_WC - p_nom) - o.extrinsic_trans).norm(), 1e-12);
  EXPECT_EQ(true_camera(o).intrinsics, o.cam.intrinsics); // the intrinsics untouched
}

// A wandering offset: td0 + A·sin(2π·t/P) at every image, no trend over whole periods.
TEST(SimPlanted, WanderingOffsetFollowsItsSine) {
  TdModelOptions o;
  o.kind = TdModelKind::Wander;
  o.td0_s = 0.010;
  o.wander_amplitude_s = 0.004;
  o.wander_period_s = 10.0;
  std::vector<int64_t> t;
  for (int k = 0; k < 400; ++k) // 20 s at 20 Hz: two whole periods
    t.push_back(1000000000 + 50000000LL * k);
  const auto im = apply_td_model(t, o);
  double mean = 0;
  for (size_t k = 0; k < im.size(); ++k) {
    EXPECT_NEAR(im[k].td_s(), 0.010 + 0.004 * std::sin(2 * M_PI * 0.05 * k / 10.0), 1e-9);
    mean += im[k].td_s() / im.size();
  }
  EXPECT_NEAR(mean, 0.010, 1e-6);
  EXPECT_EQ(parse_td_model("wander"), TdModelKind::Wander);
}
