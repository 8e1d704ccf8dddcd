// ROS 1 bags without ROS: a folder exported with `ovton export` replays to the byte-identical trajectory, and broken
// bags, wrong topics and unsupported encodings are reported naming the bag and the message.
#include "ov_core/io/bag_calibration.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_store.h"
#include "ov_core/io/kalibr_writer.h"
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/io/rosbag_writer.h"
#include "ov_sim/simulator.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>

namespace fs = std::filesystem;
using namespace ovton::core;

namespace {

#define OVTEST_REQUIRE_ROSBAG()                                                                                        \
  do {                                                                                                                 \
    if (!ovton::core::rosbag_supported())                                                                              \
      GTEST_SKIP() << "built with OVTON_WITH_ROSBAG=OFF";                                                              \
  } while (0)

fs::path ovton_binary() {
  return fs::read_symlink("/proc/self/exe").parent_path() / "ovton";
}

/// Runs `ovton ARGS`, stderr to `err`; returns the exit code.
int run_ovton(const std::string &args, const std::string &err) {
  const std::string cmd = ovton_binary().string() + " " + args + " >/dev/null 2>" + err;
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

std::string bytes_of(const std::string &file) {
  std::ifstream in(file, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_bytes(const std::string &file, const std::string &b) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(b.data(), static_cast<std::streamsize>(b.size()));
}

/// A short rendered flight (ground-truth initialisation) and its bag beside it, bag and folder sharing a stem so that
/// the bag finds the folder as its companion.
class BagTest : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    if (!rosbag_supported())
      return;
    dir_ = new ovtest::TempDir();
    ovton::sim::SimOptions o;
    o.out_dir = (*dir_) / "flight";
    o.duration_s = 4.0;
    o.seed = 11;
    ovton::sim::write_simulation(o);
    folder_ = new Dataset(load_dataset(o.out_dir));
    write_bag(*folder_, (*dir_) / "flight.bag");
  }
  static void TearDownTestSuite() {
    delete folder_;
    delete dir_;
    folder_ = nullptr;
    dir_ = nullptr;
  }
  void SetUp() override { OVTEST_REQUIRE_ROSBAG(); }
  static std::string bag() { return (*dir_) / "flight.bag"; }
  static std::string folder() { return (*dir_) / "flight"; }

  static ovtest::TempDir *dir_;
  static Dataset *folder_;
};
ovtest::TempDir *BagTest::dir_ = nullptr;
Dataset *BagTest::folder_ = nullptr;

} // namespace

TEST_F(BagTest, ReadsBackWhatWasWritten) {
  const Dataset b = load_bag(bag());
  EXPECT_EQ(b.kind, "rosbag");
  ASSERT_EQ(b.images.size(), folder_->images.size());
  ASSERT_EQ(b.imu.size(), folder_->imu.size());
  for (size_t i = 0; i < b.imu.size(); ++i) {
    ASSERT_EQ(b.imu[i].t_imu_ns, folder_->imu[i].t_imu_ns);
    ASSERT_EQ(b.imu[i].wm, folder_->imu[i].wm);
    ASSERT_EQ(b.imu[i].am, folder_->imu[i].am);
  }
  for (size_t i = 0; i < b.images.size(); i += 7) {
    ASSERT_EQ(b.images[i].t_cam_ns, folder_->images[i].t_cam_ns);
    ASSERT_TRUE(b.images[i].store);
    const cv::Mat x = load_image(b.images[i]), y = load_image(folder_->images[i]);
    ASSERT_EQ(x.size(), y.size());
    EXPECT_EQ(cv::countNonZero(x != y), 0) << "image " << i;
  }
  // The companion folder (same stem) gives calibration, ground truth and td_truth.
  EXPECT_EQ(b.cam.intrinsics, folder_->cam.intrinsics);
  EXPECT_EQ(b.cam.T_BC, folder_->cam.T_BC);
  EXPECT_EQ(b.groundtruth.size(), folder_->groundtruth.size());
  EXPECT_EQ(b.td_truth.size(), folder_->td_truth.size());
  EXPECT_NE(b.notes.find("/cam0/image_raw"), std::string::npos) << b.notes;
}

// The user's path: `ovton run` on the folder and on the bag (images read from the bag on the prefetch thread).
TEST_F(BagTest, BagReplaysToTheByteIdenticalTrajectory) {
  if (!fs::exists(ovton_binary()))
    GTEST_SKIP() << "ovton not built";
  const std::string cfg = std::string(OVTON_SOURCE_DIR) + "/config/sim/estimator_config.yaml", err = (*dir_) / "e";
  ASSERT_EQ(run_ovton("run -q -c " + cfg + " --dataset " + folder() + " -o " + ((*dir_) / "folder.csv"), err), 0)
      << ovtest::read_text(err);
  ASSERT_EQ(run_ovton("run -q -c " + cfg + " --dataset " + bag() + " -o " + ((*dir_) / "bag.csv"), err), 0)
      << ovtest::read_text(err);
  const std::string a = bytes_of((*dir_) / "folder.csv"), b = bytes_of((*dir_) / "bag.csv");
  EXPECT_GT(std::count(a.begin(), a.end(), '\n'), 50);
  EXPECT_TRUE(a == b) << "trajectories differ";
}

// Kalibr files written beside the bag are found when there is no companion folder, and give the same calibration.
TEST_F(BagTest, KalibrFilesBesideTheBag) {
  ovtest::TempDir d;
  const std::string alone = d / "alone.bag";
  const auto rep = write_bag(*folder_, alone);
  EXPECT_TRUE(fs::exists(rep.camchain_file));
  EXPECT_EQ(fs::path(rep.camchain_file).filename(), "camchain-imucam-alone.yaml");
  const Dataset b = load_bag(alone);
  EXPECT_TRUE(b.groundtruth.empty());
  EXPECT_EQ(b.cam.intrinsics, folder_->cam.intrinsics);
  EXPECT_EQ(b.cam.dist_coeffs, folder_->cam.dist_coeffs);
  EXPECT_LT((b.cam.T_BC - folder_->cam.T_BC).norm(), 1e-14);
  EXPECT_EQ(b.imu_calib.gyro_noise_density, folder_->imu_calib.gyro_noise_density);
  EXPECT_EQ(b.imu_calib.rate_hz, folder_->imu_calib.rate_hz);
  // Named explicitly, the folder wins over the Kalibr files.
  BagOptions o;
  o.calib = {folder()};
  EXPECT_EQ(load_bag(alone, o).groundtruth.size(), folder_->groundtruth.size());
  // Without any calibration: an error naming the bag and where it looked.
  fs::remove(rep.camchain_file);
  ovtest::expect_data_error([&] { load_bag(alone); }, "alone.bag", 0, "no calibration");
}

TEST_F(BagTest, TopicsChosenOrRefused) {
  BagOptions o;
  o.cam_topic = "/cam1/image_raw";
  try {
    load_bag(bag(), o);
    ADD_FAILURE() << "expected an error for a missing topic";
  } catch (const DataError &e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("flight.bag"), std::string::npos) << m;
    EXPECT_NE(m.find("no topic /cam1/image_raw"), std::string::npos) << m;
    EXPECT_NE(m.find("/imu0 [sensor_msgs/Imu]"), std::string::npos) << m; // lists what there is
  }
  o.cam_topic = "/imu0";
  try {
    load_bag(bag(), o);
    ADD_FAILURE() << "expected an error for a topic of the wrong type";
  } catch (const DataError &e) {
    EXPECT_NE(std::string(e.what()).find("topic /imu0 holds sensor_msgs/Imu, not sensor_msgs/Image"), std::string::npos)
        << e.what();
  }
  // An image topic of another name: the only one there is taken.
  ovtest::TempDir d;
  BagWriteOptions w;
  w.cam_topic = "/left/image";
  w.kalibr_files = false;
  write_bag(*folder_, d / "left.bag", w);
  o = BagOptions();
  o.calib = {folder()};
  EXPECT_EQ(load_bag(d / "left.bag", o).images.size(), folder_->images.size()); // the only image topic
}

// A stereo camchain (Kalibr: cam1 with T_cn_cnm1 and its rostopic): the calibration used is that of the camera whose
// topic is replayed, never cam0's intrinsics and lever arm on cam1's images; a topic the chain does not name is
// refused.
TEST_F(BagTest, CalibrationChosenPerCameraTopic) {
  ovtest::TempDir d;
  const std::string chain = d / "camchain-imucam.yaml", imu = d / "imu.yaml";
  write_kalibr_camchain(chain, folder_->cam, 0.0, "/cam0/image_raw");
  write_kalibr_imu(imu, folder_->imu_calib, "/imu0");
  YAML::Node y = YAML::LoadFile(chain);
  YAML::Node cam1 = YAML::Clone(y["cam0"]);
  cam1.remove("T_cam_imu");
  YAML::Node T; // cam1 11 cm to the right of cam0, as EuRoC's pair, and its own time shift
  for (const std::vector<double> row : {std::vector<double>{1, 0, 0, -0.11}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}})
    T.push_back(row);
  cam1["T_cn_cnm1"] = T;
  cam1["rostopic"] = "/cam1/image_raw";
  cam1["timeshift_cam_imu"] = 0.004;
  y["cam1"] = cam1;
  ovtest::write_text(chain, YAML::Dump(y) + "\n");

  BagWriteOptions w;
  w.kalibr_files = false;
  w.cam_topic = "/cam1/image_raw";
  write_bag(*folder_, d / "right.bag", w);
  BagOptions o;
  o.calib = {chain, imu};
  const Dataset right = load_bag(d / "right.bag", o);
  Eigen::Matrix4d T_C0C1 = Eigen::Matrix4d::Identity(); // the inverse of T_cn_cnm1
  T_C0C1(0, 3) = 0.11;
  const Eigen::Matrix4d T_BC1 = folder_->cam.T_BC * T_C0C1;
  EXPECT_LT((right.cam.T_BC - T_BC1).norm(), 1e-12) << right.cam.T_BC;
  EXPECT_DOUBLE_EQ(right.td_prior_s, 0.004);
  EXPECT_NE(right.notes.find("its cam1"), std::string::npos) << right.notes;

  // The same bag's cam0 topic gets cam0's calibration.
  w.cam_topic = "/cam0/image_raw";
  write_bag(*folder_, d / "left.bag", w);
  const Dataset left = load_bag(d / "left.bag", o);
  EXPECT_LT((left.cam.T_BC - folder_->cam.T_BC).norm(), 1e-14);
  EXPECT_EQ(left.td_prior_s, 0.0);

  // A topic the chain's two cameras do not name: refused, naming the calibration and the topics it has.
  w.cam_topic = "/left/image";
  write_bag(*folder_, d / "other.bag", w);
  try {
    load_bag(d / "other.bag", o);
    ADD_FAILURE() << "expected an error for a topic the camchain does not name";
  } catch (const DataError &e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("camchain-imucam.yaml"), std::string::npos) << m;
    EXPECT_NE(m.find("/left/image is none of the calibration's cameras (cam0 /cam0/image_raw, cam1 /cam1/image_raw)"),
              std::string::npos)
        << m;
  }
}

TEST_F(BagTest, TruncatedBagNamesTheFile) {
  ovtest::TempDir d;
  const std::string cut = d / "cut.bag";
  const std::string b = bytes_of(bag());
  write_bytes(cut, b.substr(0, b.size() / 2));
  BagOptions o;
  o.calib = {folder()};
  try {
    load_bag(cut, o);
    ADD_FAILURE() << "expected an error for a truncated bag";
  } catch (const DataError &e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("cut.bag"), std::string::npos) << m;
    EXPECT_NE(m.find("corrupt or truncated"), std::string::npos) << m;
    EXPECT_NE(m.find("`rosbag reindex` rebuilds its index"), std::string::npos) << m; // what the user can do
  }
  // Not a bag at all.
  write_bytes(d / "text.bag", "hello\n");
  ovtest::expect_data_error([&] { load_bag(d / "text.bag", o); }, "text.bag", 0, "not a bag");
}

// A message whose pixel bytes no longer fit its header: named by message index.
TEST_F(BagTest, CorruptMessageNamesTheMessage) {
  ovtest::TempDir d;
  std::string b = bytes_of(bag());
  // The first image's encoding field, "mono8", is followed by is_bigendian, step and the data length: make the step
  // wrong so that width x height x step no longer matches the data.
  const size_t at = b.find("mono8");
  ASSERT_NE(at, std::string::npos);
  b[at + 5 + 1] = static_cast<char>(b[at + 5 + 1] + 1); // step's low byte
  write_bytes(d / "corrupt.bag", b);
  BagOptions o;
  o.calib = {folder()};
  try {
    load_bag(d / "corrupt.bag", o);
    ADD_FAILURE() << "expected an error for a corrupt image message";
  } catch (const DataError &e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("corrupt.bag: message "), std::string::npos) << m;
    EXPECT_NE(m.find("(/cam0/image_raw)"), std::string::npos) << m;
    EXPECT_NE(m.find("do not fit"), std::string::npos) << m;
  }
}

TEST_F(BagTest, UnsupportedEncodingNamesTheMessage) {
  ovtest::TempDir d;
  std::string b = bytes_of(bag());
  // Every image's encoding becomes "yuv42" (same length: the message stays well-formed).
  for (size_t at = b.find("mono8"); at != std::string::npos; at = b.find("mono8", at + 5))
    b.replace(at, 5, "yuv42");
  write_bytes(d / "yuv.bag", b);
  BagOptions o;
  o.calib = {folder()};
  try {
    load_bag(d / "yuv.bag", o);
    ADD_FAILURE() << "expected an error for an unsupported encoding";
  } catch (const DataError &e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("yuv.bag: message "), std::string::npos) << m;
    EXPECT_NE(m.find("unsupported image encoding 'yuv42'"), std::string::npos) << m;
  }
  // Through the CLI: exit code 3 (data error), the message on stderr.
  if (!fs::exists(ovton_binary()))
    return;
  const std::string err = d / "err.txt";
  EXPECT_EQ(run_ovton("run -q --dataset " + (d / "yuv.bag") + " --calib " + folder() + " -o " + (d / "t.csv"), err), 3);
  EXPECT_NE(ovtest::read_text(err).find("unsupported image encoding 'yuv42'"), std::string::npos)
      << ovtest::read_text(err);
  EXPECT_EQ(run_ovton("info --dataset " + bag() + " --cam-topic /nope", err), 3);
  EXPECT_NE(ovtest::read_text(err).find("no topic /nope"), std::string::npos) << ovtest::read_text(err);
}

// A real EuRoC folder exported to a bag replays to the same trajectory (the moving cut, ground-truth start).
TEST(BagReal, EurocMovingCutByteIdentical) {
  OVTEST_REQUIRE_SHARED_DATA();
  OVTEST_REQUIRE_ROSBAG();
  if (!fs::exists(ovton_binary()))
    GTEST_SKIP() << "ovton not built";
  ovtest::TempDir d;
  const std::string folder = ovtest::shared_data() + "/euroc_v1_01_moving", err = d / "e";
  const std::string bag = d / "moving.bag";
  ASSERT_EQ(run_ovton("export -q --dataset " + folder + " --bag " + bag, err), 0) << ovtest::read_text(err);
  const std::string cfg = std::string(OVTON_SOURCE_DIR) + "/config/euroc_mav/estimator_config.yaml";
  const std::string common = "run -q -c " + cfg + " --init groundtruth --max-images 60 ";
  ASSERT_EQ(run_ovton(common + "--dataset " + folder + " -o " + (d / "folder.csv"), err), 0) << ovtest::read_text(err);
  ASSERT_EQ(run_ovton(common + "--dataset " + bag + " --calib " + folder + " -o " + (d / "bag.csv"), err), 0)
      << ovtest::read_text(err);
  const std::string a = bytes_of(d / "folder.csv"), b = bytes_of(d / "bag.csv");
  EXPECT_GT(std::count(a.begin(), a.end(), '\n'), 40);
  EXPECT_TRUE(a == b) << "trajectories differ";
}
