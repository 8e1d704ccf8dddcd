// `ovton run` hands the images the coarse t_d search decoded to the filter instead of decoding them again
// (tools/run_pipeline.cpp): the trajectory is byte-identical to decoding twice, with and without the prefetch thread,
// with a budget that keeps only some of them, and from a ROS bag.
#include "ov_core/io/rosbag_reader.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace {

fs::path ovton_binary() {
  return fs::read_symlink("/proc/self/exe").parent_path() / "ovton";
}

/// Runs `ovton ARGS` with stdout to `out`, stderr to `out`.err; returns the exit code.
int ovton(const std::string &args, const std::string &out) {
  const std::string cmd = ovton_binary().string() + " " + args + " >" + out + " 2>" + out + ".err";
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

/// How many images the run's filter took from the search, from its summary line (-1 when it has none).
int reused(const std::string &out) {
  std::smatch m;
  const std::string text = ovtest::read_text(out);
  return std::regex_search(text, m, std::regex("the filter reused ([0-9]+) of its decoded images")) ? std::stoi(m[1])
                                                                                                    : -1;
}

} // namespace

TEST(SearchImages, ReusedImagesGiveTheByteIdenticalTrajectory) {
  OVTEST_REQUIRE_SHARED_DATA();
  if (!fs::exists(ovton_binary()))
    GTEST_SKIP() << "ovton not built";
  ovtest::TempDir d;
  const std::string folder = ovtest::shared_data() + "/euroc_v1_01_moving";
  const std::string cfg = std::string(OVTON_SOURCE_DIR) + "/config/euroc_mav/estimator_config.yaml";
  const auto run = [&](const std::string &name, const std::string &extra) {
    const std::string out = d / (name + ".out");
    EXPECT_EQ(ovton("run -q -c " + cfg + " --init groundtruth -m sr -d " + folder + " -o " + (d / (name + ".csv")) +
                        " " + extra,
                    out),
              0)
        << ovtest::read_text(out + ".err");
    return reused(out);
  };
  EXPECT_EQ(run("twice", "--search-images-mb 0 --no-prefetch"), 0);
  const int all = run("once", "--no-prefetch");
  EXPECT_GT(all, 40) << "the search decoded no images: nothing was tested";
  EXPECT_EQ(run("once_prefetch", ""), all);
  EXPECT_EQ(run("some_prefetch", "--search-images-mb 1"), 2); // 752x480 bytes each
  EXPECT_EQ(run("some", "--search-images-mb 1 --no-prefetch"), 2);
  const std::string a = ovtest::read_text(d / "twice.csv");
  EXPECT_GT(std::count(a.begin(), a.end(), '\n'), 50);
  for (const char *name : {"once", "once_prefetch", "some_prefetch", "some"})
    EXPECT_TRUE(ovtest::read_text(d / (std::string(name) + ".csv")) == a) << name << " differs";

  if (!ov_core::rosbag_supported())
    return;
  const std::string bag = d / "moving.bag";
  ASSERT_EQ(ovton("export -q --dataset " + folder + " --bag " + bag, d / "export.out"), 0)
      << ovtest::read_text(d / "export.out.err");
  const std::string out = d / "bag.out";
  ASSERT_EQ(ovton("run -q -c " + cfg + " --init groundtruth -m sr -d " + bag + " --calib " + folder + " -o " +
                      (d / "bag.csv"),
                  out),
            0)
      << ovtest::read_text(out + ".err");
  EXPECT_EQ(reused(out), all);
  EXPECT_TRUE(ovtest::read_text(d / "bag.csv") == a) << "the bag's trajectory differs";
}
