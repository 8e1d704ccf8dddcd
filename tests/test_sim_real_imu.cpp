// A real IMU for semi-real folders (ov_sim/real_imu.h): read from a flat imu0 CSV as from an EuRoC folder without
// images, and the folder's ground-truth biases taken from where they are known, else measured from the log. The
// "real" log here is a noise-free synthetic one with planted constant biases, so every number has a known answer.
#include "ov_core/io/dataset.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/types/errors.h"
#include "ov_sim/real_imu.h"
#include "ov_sim/simulator.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using ovton::core::StateSample;

namespace {

const Eigen::Vector3d kBg(0.02, -0.01, 0.05), kBa(0.1, -0.05, 0.08);

/// Under `root`: flat/log.csv + flat/sensor.yaml (the planted-bias log), folder/mav0/imu0 + its ground truth with
/// the bias columns, pose.csv (the same poses, no bias columns), gt17.csv (with them).
void make_real_source(const fs::path &root) {
  ovton::sim::SimOptions o; // the built-in flight, noise-free IMU, no images
  o.out_dir = (root / "src").string();
  o.duration_s = 30.0; // match_imu needs 20 s of overlap
  o.imu_noise = false;
  o.imu_bias_walk = false;
  o.no_images = true;
  ovton::sim::write_simulation(o);
  const ovton::core::Dataset d = ovton::core::load_dataset(o.out_dir, ovton::core::LoadOptions{false});
  fs::create_directories(root / "flat");
  fs::create_directories(root / "folder/mav0/imu0");
  fs::create_directories(root / "folder/mav0/state_groundtruth_estimate0");
  {
    std::ofstream f(root / "flat/log.csv");
    f << "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
         "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
    f.precision(12);
    for (const auto &m : d.imu) {
      const Eigen::Vector3d w = m.wm + kBg, a = m.am + kBa;
      f << m.t_imu_ns << "," << w.x() << "," << w.y() << "," << w.z() << "," << a.x() << "," << a.y() << "," << a.z()
        << "\n";
    }
  }
  fs::copy_file(fs::path(o.out_dir) / "mav0/imu0/sensor.yaml", root / "flat/sensor.yaml");
  fs::copy_file(root / "flat/log.csv", root / "folder/mav0/imu0/data.csv");
  fs::copy_file(root / "flat/sensor.yaml", root / "folder/mav0/imu0/sensor.yaml");
  std::vector<StateSample> gt = d.groundtruth;
  for (auto &s : gt)
    s.bg = kBg, s.ba = kBa;
  ovton::core::write_euroc_groundtruth((root / "gt17.csv").string(), gt);
  ovton::core::write_euroc_groundtruth((root / "folder/mav0/state_groundtruth_estimate0/data.csv").string(), gt);
  std::ofstream f(root / "pose.csv");
  f << "#timestamp [ns],px,py,pz,qw,qx,qy,qz\n";
  f.precision(12);
  for (const auto &s : gt)
    f << s.t_ns << "," << s.p.x() << "," << s.p.y() << "," << s.p.z() << "," << s.q_WB.w() << "," << s.q_WB.x() << ","
      << s.q_WB.y() << "," << s.q_WB.z() << "\n";
}

} // namespace

TEST(SimRealImu, AFlatLogReadsAsTheFolderDoes) {
  ovtest::TempDir dir;
  make_real_source(dir.str());
  const ovton::sim::RealImu flat = ovton::sim::load_real_imu(dir / "flat/log.csv");
  const ovton::sim::RealImu folder = ovton::sim::load_real_imu(dir / "folder");
  ASSERT_GT(flat.imu.size(), 5000u);
  ASSERT_EQ(flat.imu.size(), folder.imu.size());
  EXPECT_EQ(flat.imu.back().t_imu_ns, folder.imu.back().t_imu_ns);
  EXPECT_EQ(flat.imu[100].wm, folder.imu[100].wm);
  EXPECT_TRUE(flat.groundtruth.empty());
  EXPECT_FALSE(folder.groundtruth.empty()); // no cam0 needed
  EXPECT_THROW(ovton::sim::load_real_imu(dir / "nothing.csv"), ovton::core::DataError);
}

TEST(SimRealImu, BiasesFromTheSourceFromGtElseMeasured) {
  ovtest::TempDir dir;
  make_real_source(dir.str());
  const auto flat = ovton::sim::load_real_imu(dir / "flat/log.csv");
  const auto folder = ovton::sim::load_real_imu(dir / "folder");
  const auto pose = ovton::core::read_trajectory(dir / "pose.csv");
  const auto gt17 = ovton::core::read_trajectory(dir / "gt17.csv");
  Eigen::Vector3d bg, ba;
  const auto from_source = ovton::sim::real_imu_biases(folder, pose, "pose", 0.1);
  EXPECT_FALSE(from_source.samples.empty());
  from_source.at(pose[500].t_ns, bg, ba);
  EXPECT_LT((bg - kBg).norm(), 1e-9);
  const auto from_gt = ovton::sim::real_imu_biases(flat, gt17, "gt17", 0.1);
  EXPECT_NE(from_gt.source.find("gt17"), std::string::npos);
  from_gt.at(pose[500].t_ns, bg, ba);
  EXPECT_LT((ba - kBa).norm(), 1e-9);
  const auto measured = ovton::sim::real_imu_biases(flat, pose, "pose", 0.1);
  EXPECT_TRUE(measured.samples.empty());
  EXPECT_NE(measured.source.find("measured"), std::string::npos);
  measured.at(pose[500].t_ns, bg, ba);
  std::cout << "[ measured ] planted biases recovered to " << (bg - kBg).norm() << " rad/s, " << (ba - kBa).norm()
            << " m/s^2\n";
  // Noise-free log: exact up to the spline's fit (measured 1.5e-8 rad/s, 7.9e-7 m/s^2).
  EXPECT_LT((bg - kBg).norm(), 1e-5);
  EXPECT_LT((ba - kBa).norm(), 1e-4);
}

TEST(SimRealImu, SimulateWritesTheFlatLogAndItsBiases) {
  ovtest::TempDir dir;
  make_real_source(dir.str());
  ovton::sim::SimOptions o;
  o.gt_file = dir / "pose.csv";
  o.imu_from = dir / "flat/log.csv";
  o.start_s = 5.0;
  o.duration_s = 10.0;
  o.no_images = true;
  o.out_dir = dir / "semi";
  ovton::sim::write_simulation(o);
  const ovton::core::Dataset d = ovton::core::load_dataset(o.out_dir, ovton::core::LoadOptions{false});
  const auto flat = ovton::sim::load_real_imu(o.imu_from);
  auto it = std::find_if(flat.imu.begin(), flat.imu.end(),
                         [&](const auto &m) { return m.t_imu_ns == d.imu.front().t_imu_ns; });
  ASSERT_NE(it, flat.imu.end()) << "the folder's IMU is not the flat log's";
  EXPECT_LT((it->wm - d.imu.front().wm).norm(), 1e-9);
  EXPECT_LT((d.groundtruth[100].bg - kBg).norm(), 1e-3);
  const YAML::Node y = YAML::LoadFile(o.out_dir + "/sim.yaml");
  EXPECT_NE(y["imu"]["bias_truth"].as<std::string>().find("measured"), std::string::npos);
}
