// Stereo recordings: a rendered stereo folder exported as a ROS 1 bag and as an MCAP file (one topic per camera, the
// Kalibr rig beside them) reads back with both cameras, their calibrations and stamps, and replays to the folder's
// stereo trajectory byte for byte.
#include "estimator_test_util.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_store.h"
#include "ov_core/io/mcap_export.h"
#include "ov_core/io/recording_export.h"
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/io/rosbag_writer.h"
#include "ov_sim/simulator.h"
#include "sim_fixture.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <sstream>

namespace {

using ovton::core::Dataset;

/// Both cameras of `b` as `a` has them: calibration, stamps and pixels of every further image.
void expect_same_rig(const Dataset &a, const Dataset &b) {
  ASSERT_EQ(b.num_cameras(), a.num_cameras()) << b.notes;
  for (size_t c = 0; c < a.more_cameras.size(); ++c) {
    const auto &x = a.more_cameras[c], &y = b.more_cameras[c];
    EXPECT_EQ(y.cam.intrinsics, x.cam.intrinsics);
    EXPECT_LT((y.cam.T_BC - x.cam.T_BC).norm(), 1e-12) << "camera " << c + 1;
    ASSERT_EQ(y.images.size(), x.images.size());
    for (size_t i = 0; i < x.images.size(); ++i) {
      ASSERT_EQ(y.images[i].t_cam_ns, x.images[i].t_cam_ns) << "image " << i;
      if (i % 10 == 0)
        EXPECT_EQ(cv::countNonZero(ovton::core::load_image(y.images[i]) != ovton::core::load_image(x.images[i])), 0)
            << "camera " << c + 1 << " image " << i;
    }
  }
}

std::string trajectory_text(const Dataset &d) {
  ovton::msckf::VioOptions opt = ovtest::gt_run_options(ovton::msckf::TdMode::Sr, 1.0);
  std::ostringstream s;
  s.precision(17);
  for (const auto &x : ovtest::run_estimator(d, opt).traj)
    s << x.t_ns << ' ' << x.p.transpose() << ' ' << x.q_WB.coeffs().transpose() << ' ' << x.td_s << '\n';
  return s.str();
}

} // namespace

TEST(StereoRecordings, BagAndMcapCarryBothCamerasAndReplayLikeTheFolder) {
  if (!ovton::core::rosbag_supported())
    GTEST_SKIP() << "built with OVTON_WITH_ROSBAG=OFF";
  ovtest::TempDir dir;
  ovton::sim::SimOptions so;
  so.out_dir = dir / "rig"; // the recordings' companion folder (same stem): calibration, ground truth
  so.duration_s = 3.0;
  so.seed = 5;
  so.cameras = 2;
  ovton::sim::write_simulation(so);
  const Dataset folder = ovton::core::load_dataset(so.out_dir);
  ASSERT_EQ(folder.num_cameras(), 2u);
  const std::string expected = trajectory_text(folder);
  EXPECT_GT(std::count(expected.begin(), expected.end(), '\n'), 30);

  // Beside the companion folder (an EuRoC folder: camN stands for /camN/image_raw), replayed from its ground truth.
  ovton::core::BagWriteOptions no_kalibr;
  no_kalibr.kalibr_files = false;
  EXPECT_EQ(ovton::core::write_bag(folder, dir / "rig.bag", no_kalibr).images, folder.images.size());
  ovton::core::McapExportOptions mo;
  mo.kalibr_files = false;
  ovton::core::write_mcap(folder, dir / "rig.mcap", mo);
  for (const std::string rec : {"rig.bag", "rig.mcap"}) {
    SCOPED_TRACE(rec);
    const Dataset d = ovton::core::load_recording(dir / rec);
    EXPECT_NE(
        d.notes.find("/cam1/image_raw (cam1, " + std::to_string(folder.more_cameras[0].images.size()) + " images)"),
        std::string::npos)
        << d.notes;
    expect_same_rig(folder, d);
    EXPECT_TRUE(trajectory_text(d) == expected) << "the stereo replay differs from the folder's";
  }
  // Alone, with the Kalibr rig the export writes beside it (cam1 with its own T_cam_imu and rostopic).
  ovtest::TempDir alone;
  const auto rep = ovton::core::write_bag(folder, alone / "walk.bag");
  EXPECT_NE(ovtest::read_text(rep.camchain_file).find("rostopic: /cam1/image_raw"), std::string::npos);
  expect_same_rig(folder, ovton::core::load_recording(alone / "walk.bag"));
  ovton::core::write_mcap(folder, alone / "walk2.mcap");
  expect_same_rig(folder, ovton::core::load_recording(alone / "walk2.mcap"));
}
