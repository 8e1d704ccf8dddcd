// A recording cut short: played up to the cut, its rows kept, then the cut named (ovton::play, exit 3).
#include "ov_core/io/mcap_export.h"
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_msckf_ton/estimator/dataset_player.h"
#include "test_mcap_util.h"

#include <gtest/gtest.h>

using namespace ovton::core;

namespace {

const std::string kSimConfig = std::string(OVTON_SOURCE_DIR) + "/config/sim/estimator_config.yaml";

/// One rendered flight for the tests of this file.
class McapRunRecorderTest : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    dir_ = new ovtest::TempDir();
    folder_ = new Dataset(load_dataset(ovtest::render_flight((*dir_) / "flight", 2.5, 12)));
  }
  static void TearDownTestSuite() {
    delete folder_;
    delete dir_;
  }
  static std::string flight() { return (*dir_) / "flight"; }
  /// The sim config without the coarse search, so that states come out while the images are fed.
  static ovton::msckf::VioOptions streaming_options() {
    ovton::msckf::VioOptions o = ovton::msckf::load_vio_options(kSimConfig);
    o.td.search.enabled = false;
    return o;
  }

  static ovtest::TempDir *dir_;
  static Dataset *folder_;
};
ovtest::TempDir *McapRunRecorderTest::dir_ = nullptr;
Dataset *McapRunRecorderTest::folder_ = nullptr;

int run_ovton(const std::string &args, const std::string &out) {
  return ovtest::shell(ovtest::ovton_binary() + " " + args, out);
}

} // namespace

// A recording cut short: `ovton run` writes the rows up to the cut, then exits 3 naming the file and the byte; the
// library's player hands out the states before throwing.
TEST_F(McapRunRecorderTest, CutRecordingKeepsItsRowsThenExits3) {
  ovtest::TempDir d;
  McapExportOptions e;
  e.mcap.chunk_size = 64u << 10;
  write_mcap(*folder_, d / "full.mcap", e);
  const std::string b = ovtest::bytes_of(d / "full.mcap");
  ovtest::write_bytes(d / "cut.mcap", b.substr(0, b.size() * 2 / 3));
  BagOptions calib;
  calib.calib = {flight()};
  const Dataset cut = load_recording(d / "cut.mcap", calib);
  ASSERT_FALSE(cut.truncated_file.empty());

  const std::string err = d / "err";
  EXPECT_EQ(run_ovton("run -q -c " + kSimConfig + " --dataset " + (d / "cut.mcap") + " --calib " + flight() + " -o " +
                          (d / "cut.csv"),
                      err),
            3);
  const std::string msg = ovtest::read_text(err);
  EXPECT_NE(msg.find("cut.mcap: the record at byte "), std::string::npos) << msg;
  EXPECT_NE(msg.find("cut short"), std::string::npos) << msg;
  EXPECT_NE(msg.find("their rows are in " + (d / "cut.csv")), std::string::npos) << msg;
  const size_t rows = read_trajectory(d / "cut.csv").size();
  EXPECT_GT(rows, 10u);

  ovton::Estimator est(ovton::setup_for(cut, streaming_options()));
  size_t states = 0;
  est.add_state_callback([&](const StateSample &) { ++states; });
  try {
    ovton::play(cut, est);
    ADD_FAILURE() << "expected the cut to be reported";
  } catch (const DataError &x) {
    EXPECT_EQ(x.file(), d / "cut.mcap");
    EXPECT_NE(std::string(x.what()).find("the record at byte "), std::string::npos) << x.what();
  }
  EXPECT_GT(states, 10u);
}
