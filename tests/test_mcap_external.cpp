// ovton's MCAP and rosbag2 readers and writers against ones that are not ovton's (scripts/mcap_tools): Foxglove's
// @mcap/core and ROS 2 CDR serializer (node), and a Python standard-library writer of rosbag2 SQLite bags. Recordings
// they make of a folder replay to the folder's trajectory byte for byte; files ovton writes (an export, a run's
// --mcap-out) are read by Foxglove's reader with every channel decoded by its schema. Skipped with a message when node
// or the npm packages (scripts/mcap_tools: npm ci) or python3 are not there; the real-data cases also need
// ../shared/data.
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_store.h"
#include "ov_core/io/mcap_export.h"
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_sim/simulator.h"
#include "test_mcap_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sys/wait.h>

namespace fs = std::filesystem;
using namespace ovton::core;

namespace {

const std::string kTools = std::string(OVTON_SOURCE_DIR) + "/scripts/mcap_tools";

std::string why_no_tools() {
  if (std::system("node --version >/dev/null 2>&1") != 0)
    return "node is not installed";
  if (!fs::exists(kTools + "/node_modules/@mcap/core"))
    return "the npm packages of scripts/mcap_tools are not installed (npm ci --prefix scripts/mcap_tools)";
  if (std::system("python3 --version >/dev/null 2>&1") != 0)
    return "python3 is not installed";
  return "";
}

#define REQUIRE_TOOLS()                                                                                                \
  do {                                                                                                                 \
    const std::string why = why_no_tools();                                                                            \
    if (!why.empty())                                                                                                  \
      GTEST_SKIP() << why << ": the independent MCAP writer and reader cannot run";                                    \
  } while (0)

using ovtest::bytes_of;
using ovtest::shell;

std::string ovton() {
  return ovtest::ovton_binary();
}

/// Runs one of scripts/mcap_tools' writers (`node write_mcap.mjs ARGS`, `python3 write_db3.py ARGS`).
void write_with(const std::string &tool, const std::string &args, const std::string &log) {
  const std::string interpreter =
      tool.size() > 3 && tool.compare(tool.size() - 3, 3, ".py") == 0 ? "python3 " : "node ";
  ASSERT_EQ(shell(interpreter + kTools + "/" + tool + " " + args, log), 0) << ovtest::read_text(log);
}

/// `node check_mcap.mjs FILE`'s JSON (the test looks for pieces of it), or a failure.
std::string foxglove_read(const std::string &file, const std::string &out) {
  EXPECT_EQ(shell("node " + kTools + "/check_mcap.mjs " + file, out), 0) << ovtest::read_text(out);
  return ovtest::read_text(out);
}

/// `ovton run` on each recording (calibrated by the folder) gives the folder's trajectory, byte for byte.
void expect_same_trajectory(const std::string &folder, const std::vector<std::string> &recordings,
                            const std::string &run_args, const std::string &dir) {
  const std::string err = dir + "/run.err";
  ASSERT_EQ(shell(ovton() + " " + run_args + " --dataset " + folder + " -o " + dir + "/folder.csv", err), 0)
      << ovtest::read_text(err);
  const std::string want = bytes_of(dir + "/folder.csv");
  EXPECT_GT(std::count(want.begin(), want.end(), '\n'), 20);
  for (const std::string &r : recordings) {
    ASSERT_EQ(shell(ovton() + " " + run_args + " --dataset " + r + " --calib " + folder + " -o " + dir + "/r.csv", err),
              0)
        << r << ": " << ovtest::read_text(err);
    const std::string got = bytes_of(dir + "/r.csv");
    EXPECT_TRUE(got == want) << r << ": the trajectory differs from the folder's (" << got.size() << " bytes, not "
                             << want.size() << "; the run said: " << ovtest::read_text(err) << ")";
  }
}

} // namespace

// A short rendered flight written by @mcap/core (indexed; and without any index) and by the Python rosbag2 writer
// (split in two .db3 files): each replays as the folder.
TEST(McapExternal, IndependentWritersReplayARenderedFolder) {
  REQUIRE_TOOLS();
  ovtest::TempDir d;
  const std::string f = ovtest::render_flight(d / "flight", 1.5, 21), log = d / "w.log";
  write_with("write_mcap.mjs", "--folder " + f + " --out " + (d / "a.mcap"), log);
  write_with("write_mcap.mjs", "--no-index --folder " + f + " --out " + (d / "b.mcap"), log);
  write_with("write_db3.py", "--split-images 16 --folder " + f + " --out " + (d / "bag"), log);
  EXPECT_NE(ovtest::read_text(log).find("\"files\": 2"), std::string::npos) << ovtest::read_text(log);
  const std::string cfg = std::string(OVTON_SOURCE_DIR) + "/config/sim/estimator_config.yaml";
  expect_same_trajectory(f, {d / "a.mcap", d / "b.mcap", d / "bag"}, "run -q -c " + cfg, d.str());
  // JPEG through both writers (jpeg-js's encoder): read, and close to the folder's pixels.
  write_with("write_mcap.mjs",
             "--images jpeg --dump-jpeg " + (d / "jpg") + " --folder " + f + " --out " + (d / "j.mcap"), log);
  write_with("write_db3.py", "--images jpeg --jpeg-from " + (d / "jpg") + " --folder " + f + " --out " + (d / "jbag"),
             log);
  BagOptions calib;
  calib.calib = {f};
  const Dataset folder = load_dataset(f);
  for (const std::string &r : {d / "j.mcap", d / "jbag"}) {
    SCOPED_TRACE(r);
    ovtest::expect_like_folder(load_recording(r, calib), folder, false, 7);
  }
}

// The real moving cut, as in BagReal: @mcap/core's raw images and the Python writer's PNG CompressedImages (its raw
// images, decoded by Python, take 10 s here: scripts/experiments/mcap_compressed_ape.sh runs them), byte-identical to
// the folder's run.
TEST(McapExternal, RealMovingCutByteIdentical) {
  REQUIRE_TOOLS();
  OVTEST_REQUIRE_SHARED_DATA();
  ovtest::TempDir d;
  const std::string folder = ovtest::shared_data() + "/euroc_v1_01_moving", log = d / "w.log";
  write_with("write_mcap.mjs", "--folder " + folder + " --out " + (d / "m.mcap"), log);
  write_with("write_db3.py", "--images png --folder " + folder + " --out " + (d / "bag"), log);
  const std::string cfg = std::string(OVTON_SOURCE_DIR) + "/config/euroc_mav/estimator_config.yaml";
  expect_same_trajectory(folder, {d / "m.mcap", d / "bag"}, "run -q -c " + cfg + " --init groundtruth --max-images 60",
                         d.str());
}

// What ovton writes opens in Foxglove's reader: an export (raw, and JPEG in lz4 chunks), every message decoded.
TEST(McapExternal, ExportReadByFoxgloveReader) {
  REQUIRE_TOOLS();
  ovtest::TempDir d;
  const Dataset folder = load_dataset(ovtest::small_folder(d / "flight", 20, 22));
  McapExportOptions e;
  write_mcap(folder, d / "raw.mcap", e);
  const std::string raw = foxglove_read(d / "raw.mcap", d / "raw.json");
  EXPECT_NE(raw.find("\"profile\":\"ros2\""), std::string::npos) << raw;
  EXPECT_NE(raw.find("\"dataCrc\":\"ok\""), std::string::npos) << raw;
  const std::string n = std::to_string(folder.images.size());
  EXPECT_NE(raw.find("\"/cam0/image_raw\":{\"schema\":\"sensor_msgs/msg/Image\",\"schemaEncoding\":\"ros2msg\","
                     "\"messageEncoding\":\"cdr\",\"count\":" +
                     n),
            std::string::npos)
      << raw;
  EXPECT_NE(raw.find("\"/imu0\":{\"schema\":\"sensor_msgs/msg/Imu\""), std::string::npos) << raw;
  EXPECT_NE(raw.find("\"/cam0/camera_info\":{\"schema\":\"sensor_msgs/msg/CameraInfo\""), std::string::npos) << raw;
  EXPECT_NE(raw.find("\"child_frame_id\":\"cam0\""), std::string::npos) << raw;
  e.image_format = "jpeg";
  e.mcap.compression = "lz4";
  write_mcap(folder, d / "jpg.mcap", e);
  const std::string jpg = foxglove_read(d / "jpg.mcap", d / "jpg.json");
  EXPECT_NE(jpg.find("\"/cam0/image_raw/compressed\":{\"schema\":\"sensor_msgs/msg/CompressedImage\""),
            std::string::npos)
      << jpg;
  EXPECT_NE(jpg.find("\"format\":\"jpeg\""), std::string::npos) << jpg;
}

// A run's --mcap-out as Foxglove reads it: every channel's schema is one Foxglove or ROS 2 defines, every message
// decodes by it, and the per-image channels hold one message per trajectory row.
TEST(McapExternal, RunMcapReadByFoxgloveReader) {
  REQUIRE_TOOLS();
  ovtest::TempDir d;
  const std::string f = ovtest::render_flight(d / "flight", 1.5, 21), err = d / "run.err";
  const std::string cfg = std::string(OVTON_SOURCE_DIR) + "/config/sim/estimator_config.yaml";
  ASSERT_EQ(shell(ovtest::ovton_binary() + " run -q -c " + cfg + " --dataset " + f + " -o " + (d / "t.csv") +
                      " --mcap-out " + (d / "run.mcap"),
                  err),
            0)
      << ovtest::read_text(err);
  const std::string n = std::to_string(read_trajectory(d / "t.csv").size());
  const std::string j = foxglove_read(d / "run.mcap", d / "run.json");
  const auto channel = [](const std::string &topic, const std::string &schema, const std::string &count) {
    return "\"" + topic + "\":{\"schema\":\"" + schema +
           "\",\"schemaEncoding\":\"ros2msg\",\"messageEncoding\":\"cdr\",\"count\":" + count;
  };
  for (const std::string &piece :
       {channel("/ovton/image", "sensor_msgs/msg/CompressedImage", n),
        channel("/ovton/features", "foxglove_msgs/msg/ImageAnnotations", n),
        channel("/ovton/pose", "geometry_msgs/msg/PoseStamped", n),
        channel("/ovton/pose_truth", "geometry_msgs/msg/PoseStamped", n), channel("/tf", "tf2_msgs/msg/TFMessage", n),
        channel("/tf_static", "tf2_msgs/msg/TFMessage", "1"), channel("/ovton/path", "nav_msgs/msg/Path", ""),
        channel("/ovton/path_truth", "nav_msgs/msg/Path", "1"), channel("/ovton/td_ms", "std_msgs/msg/Float64", n),
        channel("/ovton/td_lower_ms", "std_msgs/msg/Float64", n),
        channel("/ovton/td_upper_ms", "std_msgs/msg/Float64", n),
        channel("/ovton/td_truth_ms", "std_msgs/msg/Float64", n), std::string("\"text\":\"used "),
        std::string("\"format\":\"jpeg\""), std::string("\"dataCrc\":\"ok\"")})
    EXPECT_NE(j.find(piece), std::string::npos) << piece << "\n" << j;
}
