// `simulate` output: offset model and stamps agree exactly, same seed gives the same bytes, the folder loads
// with the EuRoC reader, feature-level mode behaves like a tracker, `perturb` restamps a real folder.
#include "ov_core/io/dataset.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/types/errors.h"
#include "ov_sim/euroc_calib.h"
#include "ov_sim/perturb.h"
#include "ov_sim/random.h"
#include "ov_sim/simulator.h"
#include "sim_test_util.h"
#include "test_util.h"

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

using namespace ovton::core;
using namespace ovton::sim;
namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path &p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

std::map<std::string, std::string> tree(const fs::path &root) {
  std::map<std::string, std::string> m;
  for (const auto &e : fs::recursive_directory_iterator(root))
    if (e.is_regular_file())
      m[fs::relative(e.path(), root).string()] = slurp(e.path());
  return m;
}

SimOptions short_drift(const std::string &out) {
  SimOptions o;
  o.out_dir = out;
  o.duration_s = 1.0;
  o.seed = 42;
  o.td.kind = TdModelKind::Drift;
  o.td.td0_s = 0.010;
  o.td.bias_s_per_s = 1e-4;
  o.td.noise_s_per_sqrt_s = 1.25e-4;
  return o;
}

} // namespace

TEST(SimTdModel, DriftRecursionAndStampsAreExact) {
  std::vector<int64_t> t;
  for (int k = 0; k < 400; ++k)
    t.push_back(1000000000000LL + k * 50000000LL);
  TdModelOptions o;
  o.kind = TdModelKind::Drift;
  o.td0_s = 0.01;
  o.bias_s_per_s = 1e-4;
  o.noise_s_per_sqrt_s = 1e-4;
  o.seed = 9;
  const auto f = apply_td_model(t, o);
  Rng rng(9);
  double td = 0.01;
  for (size_t k = 0; k < f.size(); ++k) {
    if (k > 0)
      td += 1e-4 * 0.05 + 1e-4 * std::sqrt(0.05) * rng.normal();
    EXPECT_EQ(f[k].t_imu_ns, t[k]);
    EXPECT_EQ(f[k].t_cam_ns + f[k].td_ns, t[k]);
    EXPECT_EQ(f[k].td_ns, s_to_ns(td));
  }
  // 20 s of drift: +2 ms expected, random walk sigma 0.45 ms.
  EXPECT_NEAR(f.back().td_s() - 0.01, 2e-3, 2e-3);
  o.kind = TdModelKind::Constant;
  for (const auto &c : apply_td_model(t, o))
    EXPECT_EQ(c.td_ns, 10000000);
}

TEST(SimWriter, StampsAndTdTruthAgreeWithTheModel) {
  ovtest::TempDir dir;
  SimOptions o = short_drift(dir.str());
  o.no_images = true;
  o.duration_s = 5.0;
  write_simulation(o);
  const Dataset ds = load_dataset(dir.str(), LoadOptions{false});
  const auto td = read_td_truth(dir / "mav0/td_truth/data.csv");
  ASSERT_EQ(ds.images.size(), td.size());
  ASSERT_GT(td.size(), 90u);
  // Recompute the model from the recorded seed: the files must hold exactly its output.
  std::vector<int64_t> t_imu;
  for (size_t k = 0; k < td.size(); ++k)
    t_imu.push_back(ds.imu.front().t_imu_ns + s_to_ns(o.first_image_s) + static_cast<int64_t>(k) * 50000000);
  TdModelOptions m = o.td;
  m.seed = derive_seed(o.seed, 2);
  const auto expect = apply_td_model(t_imu, m);
  for (size_t k = 0; k < td.size(); ++k) {
    EXPECT_EQ(ds.images[k].t_cam_ns, expect[k].t_cam_ns);
    EXPECT_EQ(td[k].t_cam_ns, expect[k].t_cam_ns);
    EXPECT_EQ(td[k].t_cam_ns + s_to_ns(td[k].td_s), t_imu[k]) << "t_imu = t_cam + td must hold to the ns";
  }
  EXPECT_EQ(ds.imu.size(), 1001u);
  EXPECT_EQ(ds.groundtruth.size(), ds.imu.size());
  EXPECT_EQ(ds.cam.intrinsics, euroc_cam0_calib().intrinsics);
  EXPECT_EQ(ds.cam.T_BC, euroc_cam0_calib().T_BC);
  EXPECT_EQ(ds.imu_calib.accel_random_walk, euroc_imu0_calib().accel_random_walk);
}

TEST(SimWriter, SameSeedSameBytes) {
  ovtest::TempDir a, b, c;
  for (const auto *d : {&a, &b}) {
    SimOptions o = short_drift(d->str());
    write_simulation(o);
    SimOptions f = short_drift((*d) / "features");
    f.features_only = true;
    write_simulation(f);
  }
  const auto ta = tree(a.str()), tb = tree(b.str());
  ASSERT_EQ(ta.size(), tb.size());
  EXPECT_GT(ta.size(), 20u); // images included
  for (const auto &[name, bytes] : ta) {
    ASSERT_TRUE(tb.count(name)) << name;
    EXPECT_TRUE(bytes == tb.at(name)) << name << " differs between two runs with the same seed";
  }
  SimOptions o = short_drift(c.str());
  o.seed = 43;
  o.no_images = true;
  write_simulation(o);
  EXPECT_NE(slurp(a / "mav0/imu0/data.csv"), slurp(c / "mav0/imu0/data.csv"));
}

TEST(SimWriter, FeatureModeTracksLikeATracker) {
  ovtest::TempDir dir;
  SimOptions o = short_drift(dir.str());
  o.features_only = true;
  o.duration_s = 8.0;
  write_simulation(o);
  EXPECT_FALSE(fs::exists(dir / "mav0/cam0/data") && !fs::is_empty(dir / "mav0/cam0/data"));
  std::ifstream f(dir / "mav0/cam0/features.csv");
  std::string line;
  std::getline(f, line);
  EXPECT_EQ(line, "#timestamp_ns,feature_id,u,v");
  std::map<int64_t, int> per_frame;
  std::map<uint64_t, std::pair<int, int64_t>> tracks; // id -> (length, last stamp)
  long long ts;
  unsigned long long id;
  double u, v;
  char c1, c2, c3;
  while (f >> ts >> c1 >> id >> c2 >> u >> c3 >> v) {
    ++per_frame[ts];
    auto &t = tracks[id];
    ++t.first;
    t.second = ts;
    EXPECT_TRUE(u >= -0.5 - 5 && v >= -0.5 - 5 && u < 757 && v < 485);
  }
  std::vector<int> counts, lengths;
  for (const auto &[t, n] : per_frame) {
    counts.push_back(n);
    EXPECT_LE(n, 200);
  }
  for (const auto &[i, t] : tracks)
    lengths.push_back(t.first);
  std::sort(counts.begin(), counts.end());
  std::sort(lengths.begin(), lengths.end());
  std::cout << "[ measured ] features: median " << counts[counts.size() / 2] << " per frame, median track "
            << lengths[lengths.size() / 2] << " frames, " << tracks.size() << " tracks\n";
  EXPECT_GE(counts[counts.size() / 2], 150);
  EXPECT_GE(lengths[lengths.size() / 2], 5);
  EXPECT_LT(lengths[lengths.size() / 2], 200); // tracks end
}

TEST(SimWriter, FeatureObservationsMatchTheirLandmarks) {
  // Noise-free features: every observation is the exact projection of its landmark at the true instant.
  SimOptions o;
  o.duration_s = 2.0;
  ovtest::NoiseFreeFeatureSim sim(o);
  const auto &traj = sim.traj;
  const CameraModel &cam = sim.cam;
  FeatureSimulator &fs_ = sim.features;
  for (int64_t t = traj->t_begin_ns(); t <= traj->t_end_ns(); t += 100000000) {
    Eigen::Matrix3d R_WC;
    Eigen::Vector3d p_WC;
    camera_pose(traj->sample(t), o.cam.T_BC, R_WC, p_WC);
    for (const auto &ob : fs_.step(R_WC, p_WC, t)) {
      Eigen::Vector2d uv;
      ASSERT_TRUE(cam.project(R_WC.transpose() * (fs_.landmarks()[fs_.landmark_of(ob.feature_id)] - p_WC), uv));
      EXPECT_LT((uv - ob.uv).norm(), 1e-9);
    }
  }
}

TEST(SimWriter, ShippedSensorYamlMatchesBuiltinCalibration) {
  const std::string dir = std::string(OVTON_SOURCE_DIR) + "/config/sim/";
  const CameraCalib c = load_euroc_camera_yaml(dir + "cam0_sensor.yaml"), b = euroc_cam0_calib();
  EXPECT_EQ(c.width, b.width);
  EXPECT_EQ(c.height, b.height);
  EXPECT_EQ(c.intrinsics, b.intrinsics);
  EXPECT_EQ(c.dist_coeffs, b.dist_coeffs);
  EXPECT_EQ(c.T_BC, b.T_BC);
  const ImuCalib i = load_euroc_imu_yaml(dir + "imu0_sensor.yaml"), j = euroc_imu0_calib();
  EXPECT_EQ(i.gyro_noise_density, j.gyro_noise_density);
  EXPECT_EQ(i.gyro_random_walk, j.gyro_random_walk);
  EXPECT_EQ(i.accel_noise_density, j.accel_noise_density);
  EXPECT_EQ(i.accel_random_walk, j.accel_random_walk);
}

TEST(SimPerturb, RestampsARealFolderWithLinkedImages) {
  OVTEST_REQUIRE_SHARED_DATA();
  ovtest::TempDir out;
  PerturbOptions o;
  o.in_dir = ovtest::shared_data() + "/euroc_v1_01_micro";
  o.out_dir = out.str();
  o.td.kind = TdModelKind::Drift;
  o.seed = 3;
  const auto rep = perturb_dataset(o);
  const Dataset in = load_dataset(o.in_dir), res = load_dataset(out.str());
  ASSERT_EQ(res.images.size(), in.images.size());
  EXPECT_EQ(rep.n_images, in.images.size());
  ASSERT_EQ(res.td_truth.size(), in.images.size());
  for (size_t k = 0; k < in.images.size(); ++k) {
    EXPECT_EQ(res.images[k].t_cam_ns + s_to_ns(res.td_truth[k].td_s), in.images[k].t_cam_ns);
    EXPECT_TRUE(fs::is_symlink(res.images[k].path));
    EXPECT_TRUE(fs::equivalent(res.images[k].path, in.images[k].path));
  }
  EXPECT_EQ(res.imu.size(), in.imu.size());
  EXPECT_EQ(slurp(out / "mav0/imu0/data.csv"), slurp(o.in_dir + "/mav0/imu0/data.csv"));
  EXPECT_THROW(perturb_dataset(o), UsageError); // never overwrites
}
