// Dataset readers and trajectory files: the real EuRoC folder, hand-made folders, and bad input.
#include "io_test_util.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/types/errors.h"
#include "test_util.h"

#include <filesystem>
#include <sstream>

using namespace ovton::core;
using ovtest::expect_data_error;
using ovtest::kCamYaml;
using ovtest::kImuYaml;
using ovtest::make_euroc;
using ovtest::replace_line;
using ovtest::TempDir;
using ovtest::write_text;

TEST(EurocReader, RealMicroFolder) {
  OVTEST_REQUIRE_SHARED_DATA();
  const Dataset d = load_dataset(ovtest::shared_data() + "/euroc_v1_01_micro");
  EXPECT_EQ(d.kind, "euroc");
  ASSERT_EQ(d.images.size(), 95u);
  ASSERT_EQ(d.imu.size(), 29120u);
  EXPECT_EQ(d.images.front().t_cam_ns, 1403715273262142976LL);
  EXPECT_TRUE(std::filesystem::exists(d.images.front().path));
  // First and last IMU rows, exactly as written in the file.
  EXPECT_EQ(d.imu.front().t_imu_ns, 1403715273262142976LL);
  EXPECT_EQ(d.imu.front().wm, Eigen::Vector3d(-0.0020943951023931952, 0.017453292519943295, 0.07749261878854824));
  EXPECT_EQ(d.imu.front().am, Eigen::Vector3d(9.0874956666666655, 0.13075533333333333, -3.6938381666666662));
  EXPECT_EQ(d.imu.back().t_imu_ns, 1403715418857143040LL);
  EXPECT_EQ(d.imu.back().wm, Eigen::Vector3d(-0.00069813170079773186, 0.023736477827122883, 0.074001960284559576));
  EXPECT_EQ(d.imu.back().am, Eigen::Vector3d(9.1610455416666667, 0.26151066666666667, -3.2035056666666666));
  // cam0 calibration, exact.
  EXPECT_EQ(d.cam.width, 752);
  EXPECT_EQ(d.cam.height, 480);
  EXPECT_EQ(d.cam.intrinsics, Eigen::Vector4d(458.654, 457.296, 367.215, 248.375));
  EXPECT_EQ(d.cam.distortion, DistortionModel::RadTan);
  EXPECT_EQ(d.cam.dist_coeffs, Eigen::Vector4d(-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05));
  Eigen::Matrix4d T;
  T << 0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975, 0.999557249008, 0.0149672133247,
      0.025715529948, -0.064676986768, -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949, 0, 0, 0, 1;
  EXPECT_EQ(d.cam.T_BC, T);
  EXPECT_DOUBLE_EQ(d.imu_calib.gyro_noise_density, 1.6968e-04);
  EXPECT_DOUBLE_EQ(d.imu_calib.accel_random_walk, 3.0e-3);
  // Ground truth (short '#time(ns),px,...' header), 2895 rows at 20 Hz.
  ASSERT_TRUE(d.has_groundtruth());
  EXPECT_EQ(d.groundtruth.size(), 2895u);
  EXPECT_EQ(d.groundtruth.front().t_ns, 1403715273262142976LL);
  EXPECT_DOUBLE_EQ(d.groundtruth.front().p.x(), 0.878895);
  EXPECT_DOUBLE_EQ(d.groundtruth.front().q_WB.w(),
                   Eigen::Quaterniond(0.069433, -0.824237, -0.106942, -0.551702).normalized().w());
  EXPECT_TRUE(d.groundtruth.front().has_velocity);
  EXPECT_FALSE(d.has_td_truth());
}

TEST(TrajectoryReader, RealGroundTruthTextAndCsv) {
  OVTEST_REQUIRE_SHARED_DATA();
  const auto txt = read_trajectory(ovtest::shared_data() + "/euroc_groundtruth/V1_01_easy.txt");
  ASSERT_GT(txt.size(), 10000u);
  EXPECT_EQ(txt.front().t_ns, 1403715274302140000LL); // "1403715274.30214" without double rounding
  EXPECT_DOUBLE_EQ(txt.front().p.z(), 0.947262);
  EXPECT_NEAR(txt.front().q_WB.x(), -0.828459, 1e-6);
  const auto csv = read_trajectory(ovtest::shared_data() + "/euroc_groundtruth/V1_02_medium.csv");
  EXPECT_EQ(csv.front().t_ns, 1403715524907143168LL);
  EXPECT_DOUBLE_EQ(csv.front().ba.z(), 0.093086);
}

TEST(EurocReader, SmallFolderAndMav0Path) {
  TempDir tmp;
  const std::string root = make_euroc(tmp);
  const Dataset a = load_dataset(root);
  const Dataset b = load_dataset(root + "/mav0");
  EXPECT_EQ(a.images.size(), 5u);
  EXPECT_EQ(b.imu.size(), 201u);
  EXPECT_EQ(a.groundtruth.size(), 21u);
}

TEST(EurocReader, TdTruth) {
  TempDir tmp;
  const std::string root = make_euroc(tmp);
  std::filesystem::create_directories(root + "/mav0/td_truth");
  write_td_truth(root + "/mav0/td_truth/data.csv", {{1050000000LL, 0.010}, {1100000000LL, 0.012}});
  const Dataset d = load_dataset(root);
  ASSERT_TRUE(d.has_td_truth());
  EXPECT_DOUBLE_EQ(d.td_truth_at(1075000000LL), 0.011);
  EXPECT_DOUBLE_EQ(d.td_truth_at(0), 0.010);
}

TEST(EurocReaderBadInput, MissingFolderAndFiles) {
  TempDir tmp;
  expect_data_error([&] { load_dataset(tmp / "nope"); }, "nope", 0, "missing folder");
  const std::string root = make_euroc(tmp);
  std::filesystem::remove(root + "/mav0/imu0/data.csv");
  expect_data_error([&] { load_dataset(root); }, "imu0/data.csv", 0, "missing imu csv");
  std::filesystem::remove(root + "/mav0/cam0/sensor.yaml");
  expect_data_error([&] { load_dataset(root); }, "cam0/sensor.yaml", 0, "missing camera yaml");
}

TEST(EurocReaderBadInput, RowErrorsNameFileAndLine) {
  struct Case {
    const char *file;
    int line;
    const char *text;
    const char *why;
  };
  const Case cases[] = {
      {"imu0/data.csv", 4, "1010000000,0.01,zero,0.03,0.1,0.2,9.81", "malformed number"},
      {"imu0/data.csv", 5, "1015000000,0.01,0.02,0.03,0.1,0.2", "wrong column count"},
      {"imu0/data.csv", 6, "1010000000,0.01,0.02,0.03,0.1,0.2,9.81", "non-monotonic timestamp"},
      {"imu0/data.csv", 7, "1020000000,0.01,0.02,0.03,0.1,0.2,9.81", "duplicate timestamp"},
      {"imu0/data.csv", 8, "1030000000,0.01,nan,0.03,0.1,0.2,9.81", "NaN"},
      // The last reading 305 ms after the one before: within a second of the images, longer than is propagated through.
      {"imu0/data.csv", 202, "2300000000,0.01,0.02,0.03,0.1,0.2,9.81", "IMU gap"},
      {"cam0/data.csv", 3, "1100000000,missing.png", "listed image missing"},
      {"cam0/data.csv", 4, "1100000000,1100000000.png", "duplicate image stamp"},
      {"cam0/data.csv", 2, "10x50000000,1050000000.png", "malformed image stamp"},
      {"state_groundtruth_estimate0/data.csv", 3, "1050000000,0.1,0,1,1,0,0,0,2,0,0,0,0,0,0,0", "gt columns"},
      {"state_groundtruth_estimate0/data.csv", 4, "1100000000,0.1,0,1,1,0,0,0,inf,0,0,0,0,0,0,0,0", "gt inf"},
  };
  for (const Case &c : cases) {
    TempDir tmp;
    const std::string root = make_euroc(tmp);
    replace_line(root + "/mav0/" + c.file, c.line, c.text);
    expect_data_error([&] { load_dataset(root); }, c.file, c.line, c.why);
  }
}

TEST(EurocReaderBadInput, YamlProblems) {
  {
    TempDir tmp;
    const std::string root = make_euroc(tmp);
    write_text(root + "/mav0/cam0/sensor.yaml", "intrinsics: [1, 2\nresolution: {\n");
    expect_data_error([&] { load_dataset(root); }, "cam0/sensor.yaml", 0, "unreadable YAML");
  }
  {
    TempDir tmp;
    const std::string root = make_euroc(tmp);
    std::string y = kCamYaml;
    y.replace(y.find("intrinsics: [458.654, "), 22, "intrinsics: [");
    write_text(root + "/mav0/cam0/sensor.yaml", y);
    expect_data_error([&] { load_dataset(root); }, "cam0/sensor.yaml", 0, "3 intrinsics");
  }
  {
    TempDir tmp;
    const std::string root = make_euroc(tmp);
    std::string y = kImuYaml;
    y.replace(y.find("gyroscope_noise_density"), 23, "gyro_noise");
    write_text(root + "/mav0/imu0/sensor.yaml", y);
    expect_data_error([&] { load_dataset(root); }, "imu0/sensor.yaml", 0, "missing key");
  }
}

TEST(TrajectoryFiles, CsvRoundTripAndFlushPerRow) {
  TempDir tmp;
  const std::string f = tmp / "traj.csv";
  std::vector<StateSample> rows;
  for (int i = 0; i < 3; ++i) {
    StateSample s;
    s.t_ns = 1403715273262142976LL + i * 50000000LL;
    s.p = Eigen::Vector3d(1.5 + i, -2.25, 0.125);
    s.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(0.3 * i, Eigen::Vector3d(1, 2, 3).normalized()));
    s.v = Eigen::Vector3d(0.5, 0, -i);
    s.bg = Eigen::Vector3d(1e-3, 2e-3, 3e-3);
    s.ba = Eigen::Vector3d(0.01, 0.02, 0.03);
    s.td_s = 0.0101234567;
    s.td_sigma_s = 1.5e-4;
    rows.push_back(s);
  }
  TrajectoryWriter w(f);
  for (const auto &s : rows)
    w.write(s);
  // The writer is still open (as in an interrupted run): every row must already be on disk.
  const auto back = read_trajectory(f);
  ASSERT_EQ(back.size(), rows.size());
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(back[i].t_ns, rows[i].t_ns);
    EXPECT_NEAR((back[i].p - rows[i].p).norm(), 0, 1e-8);
    EXPECT_NEAR(back[i].q_WB.angularDistance(rows[i].q_WB), 0, 1e-7);
    EXPECT_NEAR(back[i].td_s, rows[i].td_s, 1e-12);
    EXPECT_NEAR(back[i].td_sigma_s, rows[i].td_sigma_s, 1e-12);
    EXPECT_TRUE(back[i].has_td);
  }
  EXPECT_EQ(ovtest::read_text(f).substr(0, 13), "timestamp_ns,");
}

TEST(TrajectoryFiles, TumRoundTrip) {
  TempDir tmp;
  const std::string f = tmp / "traj.txt";
  StateSample s;
  s.t_ns = 1403715273262142976LL;
  s.p = Eigen::Vector3d(1, 2, 3);
  s.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()));
  {
    TrajectoryWriter w(f, TrajectoryFormat::Tum);
    w.write(s);
  }
  const auto back = read_trajectory(f);
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].t_ns, s.t_ns);
  EXPECT_NEAR(back[0].q_WB.angularDistance(s.q_WB), 0, 1e-8);
  EXPECT_FALSE(back[0].has_td);
}

TEST(TrajectoryFiles, PositionOnlyAndBadRows) {
  TempDir tmp;
  write_text(tmp / "rtk.csv", "#timestamp_ns,px,py,pz\n100,1,2,3\n200,1,2,4\n");
  const auto rtk = read_trajectory(tmp / "rtk.csv");
  ASSERT_EQ(rtk.size(), 2u);
  EXPECT_FALSE(rtk[0].has_orientation);
  write_text(tmp / "bad.txt", "# timestamp(s) tx ty tz qx qy qz qw\n1.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n");
  expect_data_error([&] { read_trajectory(tmp / "bad.txt"); }, "bad.txt", 3, "duplicate TUM stamp");
  write_text(tmp / "badq.txt", "1.0 0 0 0 0 0 0 2\n");
  expect_data_error([&] { read_trajectory(tmp / "badq.txt"); }, "badq.txt", 1, "non-unit quaternion");
  write_text(tmp / "cols.csv", "1,2,3,4,5\n");
  expect_data_error([&] { read_trajectory(tmp / "cols.csv"); }, "cols.csv", 1, "unknown layout");
  write_text(tmp / "empty.csv", "#only a header\n");
  expect_data_error([&] { read_trajectory(tmp / "empty.csv"); }, "empty.csv", 0, "no rows");
}

TEST(ScubeReader, BundledSample) {
  const Dataset d = load_dataset(std::string(OVTON_SOURCE_DIR) + "/datasets/scube_sample");
  EXPECT_EQ(d.kind, "scube");
  EXPECT_EQ(d.images.size(), 20u);
  EXPECT_EQ(d.imu.size(), 201u);
  EXPECT_EQ(d.cam.width, 320);
  EXPECT_EQ(d.cam.intrinsics, Eigen::Vector4d(400, 400, 160, 128));
  EXPECT_DOUBLE_EQ(d.td_prior_s, 0.003);
  // Kalibr T_cam_imu is inverted into T_BC: the camera's optical axis is the body x axis.
  EXPECT_NEAR((d.cam.T_BC.block<3, 1>(0, 2) - Eigen::Vector3d::UnitX()).norm(), 0, 1e-12);
  EXPECT_NEAR((d.cam.T_BC.block<3, 1>(0, 3) - Eigen::Vector3d(0.05, 0, 0)).norm(), 0, 1e-12);
  ASSERT_TRUE(d.has_groundtruth());
  EXPECT_FALSE(d.groundtruth.front().has_orientation); // RTK: position only
  EXPECT_DOUBLE_EQ(d.imu_calib.gyro_noise_density, 1e-3);
}
