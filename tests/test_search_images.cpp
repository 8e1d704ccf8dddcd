// `ovton run` hands the coarse t_d search's work to the filter (tools/run_pipeline.cpp): its tracks when its window
// starts at the first image, else the images it decoded. The trajectory is byte-identical to decoding and tracking
// twice, with and without the decoding and tracking threads, with a budget that keeps only some images, and from a
// ROS bag.
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
int run_ovton(const std::string &args, const std::string &out) {
  const std::string cmd = ovton_binary().string() + " " + args + " >" + out + " 2>" + out + ".err";
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

/// How many decoded images and tracked images the run's filter took from the search, from its summary line
/// ({-1, -1} when it has none).
std::pair<int, int> reused(const std::string &out) {
  std::smatch m;
  const std::string text = ovtest::read_text(out);
  return std::regex_search(text, m,
                           std::regex("the filter reused ([0-9]+) of its decoded images and the tracks of ([0-9]+)"))
             ? std::make_pair(std::stoi(m[1]), std::stoi(m[2]))
             : std::make_pair(-1, -1);
}

} // namespace

TEST(SearchImages, ReusedTracksAndImagesGiveTheByteIdenticalTrajectory) {
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
    return reused(out);
  };
  using P = std::pair<int, int>;
  EXPECT_EQ(run("twice", "--search-images-mb 0 --search-tracks off --no-prefetch"), P(0, 0));
  // The cut's search window starts at its first image: the filter takes its tracks (and then needs no images of it).
  const int tracked = run("tracks", "--no-prefetch").second;
  EXPECT_GT(tracked, 40) << "the search handed over no tracks: nothing was tested";
  EXPECT_EQ(run("tracks_threads", ""), P(0, tracked));
  EXPECT_EQ(run("tracks_decode_thread", "--no-track-thread"), P(0, tracked));
  const int all = run("images", "--search-tracks off --no-prefetch").first;
  EXPECT_GT(all, 40) << "the search decoded no images: nothing was tested";
  EXPECT_EQ(run("images_prefetch", "--search-tracks off"), P(all, 0));
  EXPECT_EQ(run("some_prefetch", "--search-tracks off --search-images-mb 1"), P(2, 0)); // 752x480 bytes each
  EXPECT_EQ(run("some", "--search-tracks off --search-images-mb 1 --no-prefetch"), P(2, 0));
  const std::string a = ovtest::read_text(d / "twice.csv");
  EXPECT_GT(std::count(a.begin(), a.end(), '\n'), 50);
  for (const char *name :
       {"tracks", "tracks_threads", "tracks_decode_thread", "images", "images_prefetch", "some_prefetch", "some"})
    EXPECT_TRUE(ovtest::read_text(d / (std::string(name) + ".csv")) == a) << name << " differs";

  // `compare` shares the search's tracks among its modes: each goes on from a clone of the search's tracker, and
  // gets the trajectory `run` gets, the mode without a search (off) as well.
  const std::string cmp = d / "cmp";
  ASSERT_EQ(run_ovton("compare -c " + cfg + " --init groundtruth --modes off,sr --jobs 2 --dataset " + folder +
                          " --out " + cmp,
                      d / "cmp.out"),
            0)
      << ovtest::read_text(d / "cmp.out.err");
  EXPECT_NE(ovtest::read_text(d / "cmp.out.err").find("every mode takes its tracks of " + std::to_string(tracked)),
            std::string::npos)
      << ovtest::read_text(d / "cmp.out.err");
  EXPECT_TRUE(ovtest::read_text(cmp + "/traj_sr.csv") == a) << "compare's sr differs from run's";
  EXPECT_EQ(run("off", "--no-prefetch", "off"), P(-1, -1)); // no search: no summary line
  EXPECT_TRUE(ovtest::read_text(cmp + "/traj_off.csv") == ovtest::read_text(d / "off.csv"))
      << "compare's off differs from run's";

  if (!ovton::core::rosbag_supported())
    return;
  const std::string bag = d / "moving.bag";
  ASSERT_EQ(run_ovton("export -q --dataset " + folder + " --bag " + bag, d / "export.out"), 0)
      << ovtest::read_text(d / "export.out.err");
  const std::string out = d / "bag.out";
  ASSERT_EQ(run_ovton("run -q -c " + cfg + " --init groundtruth -m sr -d " + bag + " --calib " + folder + " -o " +
                          (d / "bag.csv"),
                      out),
            0)
      << ovtest::read_text(out + ".err");
  EXPECT_EQ(reused(out), P(0, tracked));
  EXPECT_TRUE(ovtest::read_text(d / "bag.csv") == a) << "the bag's trajectory differs";
}
