// Every way `ovton` runs a recording gives the same trajectory, byte for byte: tracking and filter on threads of their
// own or everything on one thread, a mode run alone or inside `compare`, a folder or the same recording as a ROS bag —
// on the real moving cut, where the coarse t_d search holds the images until it has decided.
#include "ov_core/io/rosbag_reader.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace {

fs::path ovton_binary() {
  return fs::read_symlink("/proc/self/exe").parent_path() / "ovton";
}

/// Runs `ovton ARGS` with stdout to `out`, stderr to `out`.err; returns the exit code.
int run_ovton(const std::string &args, const std::string &out) {
  const std::string cmd = ovton_binary().string() + " " + args + " >" + out + " 2>" + out + ".err";
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

} // namespace

TEST(RunPaths, ThreadsCompareAndBagGiveTheByteIdenticalTrajectory) {
  OVTEST_REQUIRE_SHARED_DATA();
  if (!fs::exists(ovton_binary()))
    GTEST_SKIP() << "ovton not built";
  ovtest::TempDir d;
  const std::string folder = ovtest::shared_data() + "/euroc_v1_01_moving";
  const std::string cfg = std::string(OVTON_SOURCE_DIR) + "/config/euroc_mav/estimator_config.yaml";
  const auto run = [&](const std::string &name, const std::string &extra, const std::string &mode = "sr") {
    const std::string out = d / (name + ".out");
    EXPECT_EQ(run_ovton("run -q -c " + cfg + " --init groundtruth -m " + mode + " -d " + folder + " -o " +
                            (d / (name + ".csv")) + " " + extra,
                        out),
              0)
        << ovtest::read_text(out + ".err");
    return ovtest::read_text(d / (name + ".csv"));
  };
  const std::string a = run("one_thread", "--no-prefetch");
  EXPECT_GT(std::count(a.begin(), a.end(), '\n'), 50);
  EXPECT_NE(ovtest::read_text(d / "one_thread.out").find("coarse t_d search: t_d"), std::string::npos)
      << "the search found nothing on the cut: its hand-over was not tested";
  EXPECT_TRUE(run("threads", "") == a) << "threaded run differs";

  // `compare` runs each mode as `run` does.
  const std::string cmp = d / "cmp";
  ASSERT_EQ(run_ovton("compare -c " + cfg + " --init groundtruth --modes off,sr --jobs 2 --dataset " + folder +
                          " --out " + cmp,
                      d / "cmp.out"),
            0)
      << ovtest::read_text(d / "cmp.out.err");
  EXPECT_TRUE(ovtest::read_text(cmp + "/traj_sr.csv") == a) << "compare's sr differs from run's";
  EXPECT_TRUE(ovtest::read_text(cmp + "/traj_off.csv") == run("off", "--no-prefetch", "off"))
      << "compare's off differs from run's";

  if (!ovton::core::rosbag_supported())
    return;
  const std::string bag = d / "moving.bag";
  ASSERT_EQ(run_ovton("export -q --dataset " + folder + " --bag " + bag, d / "export.out"), 0)
      << ovtest::read_text(d / "export.out.err");
  ASSERT_EQ(run_ovton("run -q -c " + cfg + " --init groundtruth -m sr -d " + bag + " --calib " + folder + " -o " +
                          (d / "bag.csv"),
                      d / "bag.out"),
            0)
      << ovtest::read_text(d / "bag.out.err");
  EXPECT_TRUE(ovtest::read_text(d / "bag.csv") == a) << "the bag's trajectory differs";
}
