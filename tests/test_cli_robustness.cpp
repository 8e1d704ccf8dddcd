// The command line on input a hostile user tried (issue 12): each case exits non-zero with a message naming the file
// (and line), before any long work where it can; a diverged estimate exits 4 and `compare` reports it as failed.
// Runs the ovton binary built beside this test.
#include "io_test_util.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_sim/simulator.h"
#include "test_util.h"

#include <opencv2/imgcodecs.hpp>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sys/wait.h>

namespace fs = std::filesystem;
using ovtest::TempDir;
using ovtest::write_text;

namespace {

struct Cli {
  int code = -1;
  std::string out, err;
};

class CliRobustness : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<TempDir>();
    // A feature-level flight (+10 ms): the filter runs it in a second, and it initialises from its ground truth.
    ovton::sim::write_simulation(ovtest::feature_sim((*dir_) / "sim", 8.0, 5));
  }
  static void TearDownTestSuite() { dir_.reset(); }

  void SetUp() override {
    if (!fs::exists(ovton()))
      GTEST_SKIP() << ovton() << " not built";
  }
  static std::string ovton() { return (fs::read_symlink("/proc/self/exe").parent_path() / "ovton").string(); }
  static std::string sim() { return (*dir_) / "sim"; }

  /// `ovton args`, with stdout and stderr captured.
  Cli run(const std::string &args) const {
    const std::string out = tmp_ / "stdout.txt", err = tmp_ / "stderr.txt";
    const int rc = std::system((ovton() + " " + args + " >" + out + " 2>" + err).c_str());
    Cli c;
    c.code = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
    c.out = ovtest::read_text(out);
    c.err = ovtest::read_text(err);
    return c;
  }
  /// Exit code and a message naming `where` ("file:line" or a path).
  void expect_failure(const Cli &c, int code, const std::string &where) const {
    EXPECT_EQ(c.code, code) << c.err << c.out;
    EXPECT_NE(c.err.find(where), std::string::npos) << "message does not name " << where << ":\n" << c.err;
  }

  TempDir tmp_;
  static std::unique_ptr<TempDir> dir_;
};
std::unique_ptr<TempDir> CliRobustness::dir_;

} // namespace

TEST_F(CliRobustness, BadReadingsAndStampsAreDataErrorsNamingFileAndLine) {
  const std::string root = ovtest::make_euroc(tmp_);
  const std::string imu = root + "/mav0/imu0/data.csv", cam = root + "/mav0/cam0/data.csv";
  const std::string imu_text = ovtest::read_text(imu), cam_text = ovtest::read_text(cam);
  ovtest::replace_line(imu, 5, "1015000000,0.01,0.02,0.03,1e308,0.2,9.81");
  expect_failure(run("run --dataset " + root + " --output " + (tmp_ / "t.csv")), 3, "imu0/data.csv:5:");
  EXPECT_FALSE(fs::exists(tmp_ / "t.csv")); // refused while loading, before any row
  write_text(imu, imu_text);
  ovtest::replace_line(cam, 2, "-1050000000,1050000000.png");
  expect_failure(run("info --dataset " + root), 3, "cam0/data.csv:2:");
  write_text(cam, "#timestamp [ns],filename\n1050,1050000000.png\n1100,1100000000.png\n1150,1150000000.png\n");
  expect_failure(run("info --dataset " + root), 3, "cam0/data.csv:3:"); // milliseconds
  write_text(cam, cam_text);
  const std::string imu_yaml = root + "/mav0/imu0/sensor.yaml";
  write_text(imu_yaml, std::string(ovtest::kImuYaml) + "rate_hz: 100\n");
  expect_failure(run("info --dataset " + root), 3, "imu0/sensor.yaml:8:"); // the key set twice
  write_text(imu_yaml, ovtest::kImuYaml);
  ovtest::replace_line(imu_yaml, 6, "accelerometer_noise_density: -2.0e-3");
  expect_failure(run("info --dataset " + root), 3, "imu0/sensor.yaml:6:");
  // A byte order mark is accepted.
  write_text(root + "/mav0/imu0/sensor.yaml", ovtest::kImuYaml);
  write_text(cam, std::string("\xEF\xBB\xBF") + cam_text);
  const Cli ok = run("info --dataset " + root);
  EXPECT_EQ(ok.code, 0) << ok.err;
}

TEST_F(CliRobustness, BadOptionsAndConfigsFailBeforeTheRun) {
  const std::string traj = tmp_ / "traj.csv";
  expect_failure(run("run --dataset " + sim() + " --output " + traj + " --td-init-ms inf"), 2, "--td-init-ms");
  // NaN meant "not given" and ran with the config's offset; 0 and negative counts meant "no limit"; '-' made a file
  // '-'.
  expect_failure(run("run --dataset " + sim() + " --output " + traj + " --td-init-ms nan"), 2, "--td-init-ms");
  expect_failure(run("run --dataset " + sim() + " --output " + traj + " --max-images 0"), 2, "--max-images");
  expect_failure(run("run --dataset " + sim() + " --output " + traj + " --max-images -5"), 2, "--max-images");
  expect_failure(run("run --dataset " + sim() + " --output -"), 2, "standard output");
  // A stray word (a config override as the experiment scripts write them, a second dataset) was dropped silently.
  expect_failure(run("run --dataset " + sim() + " --output " + traj + " time_offset.model_check=false"), 2,
                 "unexpected argument 'time_offset.model_check=false'");
  expect_failure(run("compare --dataset " + sim() + " --out " + (tmp_ / "cmp") + " extra"), 2, "unexpected argument");
  EXPECT_FALSE(fs::exists(traj));
  EXPECT_FALSE(fs::exists("-"));
  expect_failure(run("run --dataset " + sim() + " --output " + traj + " --td-search maybe"), 2, "--td-search");
  expect_failure(run("run --dataset " + sim() + " --output " + traj + " --health-checks 1"), 2, "--health-checks");
  for (const auto &[text, where] : std::vector<std::pair<std::string, std::string>>{
           {"init:\n  window_s: -1\n", "bad.yaml: "},
           {"update:\n  sigma_px: 1.0\nimu:\n  gravity_mag: 0\n", "bad.yaml: "},
           {"update:\n  max_clones: 11\n  sigma_px: 1.0\n  max_clones: 30\n", "bad.yaml:4:"},
           {"update:\n  sigma_px: 1.0\ntime_offset:\n  mode: [sr, ton]\n", "bad.yaml:4:"}}) {
    write_text(tmp_ / "bad.yaml", text);
    expect_failure(run("run --dataset " + sim() + " --output " + traj + " --config " + (tmp_ / "bad.yaml")), 3, where);
  }
  // Outputs are checked before the run: a --nees-log into a missing folder costs nothing and writes nothing.
  expect_failure(run("run --dataset " + sim() + " --init groundtruth --output " + traj + " --nees-log " +
                     (tmp_ / "missing/nees.csv")),
                 3, "missing/nees.csv");
  EXPECT_FALSE(fs::exists(traj));
  expect_failure(run("run --dataset " + sim() + " --output " + traj + " --residual-log " + traj), 2, "same file");
}

TEST_F(CliRobustness, NoPoseIsAnErrorAndAWrongSizedImageNamesItsFile) {
  // The bundled SCube sample has 1 s of IMU: a 30 s still window never initialises, so no pose is estimated.
  const std::string scube = tmp_ / "scube";
  fs::copy(std::string(OVTON_SOURCE_DIR) + "/datasets/scube_sample", scube, fs::copy_options::recursive);
  write_text(tmp_ / "long_init.yaml", "init:\n  window_s: 30\n");
  const Cli none =
      run("run --dataset " + scube + " --output " + (tmp_ / "t.csv") + " --config " + (tmp_ / "long_init.yaml"));
  expect_failure(none, 3, "no pose was estimated");
  // One image of another size than the calibration's.
  const std::string first = scube + "/cam0/data/1700000000000000000.png";
  cv::imwrite(first, cv::Mat(20, 30, CV_8UC1, cv::Scalar(128)));
  expect_failure(run("run --dataset " + scube + " --output " + (tmp_ / "t.csv")), 3, "1700000000000000000.png");
}

// A 4000 m/s^2 reading in flight (inside the reader's range): the filter diverges, `run` exits 4 saying so (the rows
// before it kept), and `compare` shows every mode as failed with that reason and exits non-zero.
TEST_F(CliRobustness, DivergedEstimateFailsRunAndCompare) {
  const std::string spiked = tmp_ / "spiked";
  fs::copy(sim(), spiked, fs::copy_options::recursive);
  const std::string imu = spiked + "/mav0/imu0/data.csv";
  std::istringstream in(ovtest::read_text(imu));
  std::ostringstream out;
  std::string line;
  for (int i = 0; std::getline(in, line); ++i) {
    if (i == 800) // 4 s into the flight
      line = line.substr(0, line.find(',')) + ",0,0,0,4000,-4000,4000";
    out << line << "\n";
  }
  write_text(imu, out.str());
  const std::string traj = tmp_ / "traj.csv";
  const Cli r = run("run --dataset " + spiked + " --init groundtruth --output " + traj);
  expect_failure(r, 4, "estimate failed");
  EXPECT_NE(r.err.find(traj), std::string::npos) << r.err;
  const auto rows = ovton::core::read_trajectory(traj);
  EXPECT_GT(rows.size(), 20u);
  for (const auto &s : rows)
    ASSERT_TRUE(s.p.allFinite());
  const Cli c =
      run("compare --dataset " + spiked + " --init groundtruth --modes sr,oracle --jobs 1 --out " + (tmp_ / "cmp"));
  EXPECT_EQ(c.code, 1) << c.err;
  const std::string csv = ovtest::read_text(tmp_ / "cmp/results.csv");
  EXPECT_NE(csv.find("sr,\"failed: the estimate has diverged"), std::string::npos) << csv;
  EXPECT_NE(csv.find("oracle,\"failed: the estimate has diverged"), std::string::npos) << csv;
}

// The paper's SIR (backward velocities, none for first observations, no adaptive noise) on a fast start walks from 0
// to 80-98 ms with sigma 0.2-0.4 ms (truth 10 ms) and used to exit 0 (docs/robustness.md). Whatever the estimator
// does here, it must either end within 1 ms of the truth or fail.
TEST_F(CliRobustness, PaperSirOnAFastStartConvergesOrFailsNeverAConfidentWrongAnswer) {
  write_text(tmp_ / "paper_sir.yaml",
             "time_offset:\n  sir_velocity: backward\n  first_velocity: none\n  adaptive_noise: false\n");
  for (const char *mode : {"sir", "ton"}) {
    const std::string traj = tmp_ / (std::string(mode) + ".csv");
    const Cli r =
        run("run --dataset " + sim() + " --config " + (tmp_ / "paper_sir.yaml") +
            " --init groundtruth --td-search off --td-mode " + mode + " --td-init-ms 0 --output " + traj + " -q");
    if (r.code == 4) {
      EXPECT_NE(r.err.find("estimate failed"), std::string::npos) << r.err;
      continue;
    }
    ASSERT_EQ(r.code, 0) << mode << ": " << r.err;
    EXPECT_NEAR(ovton::core::read_trajectory(traj).back().td_s, 0.010, 0.001) << mode << " exited 0 with a wrong t_d";
  }
}
