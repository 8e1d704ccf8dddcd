// ovton::Estimator, the facade a program embeds: the same trajectory byte for byte whatever the threads and whatever
// the order IMU readings and images arrive in (images ahead of the IMU that covers them, bursts, jitter); images past
// the IMU skipped and counted; bad feeds refused with the reason; poll, status and stop as documented.
#include "estimator_test_util.h"
#include "ov_core/io/image_io.h"
#include "ov_core/types/errors.h"
#include "ov_sim/simulator.h"
#include "sim_fixture.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>

using namespace ovton;
using ovton::core::StateSample;

namespace {

/// A short rendered flight (images, IMU, ground truth), written once for the tests below.
const core::Dataset &image_flight() {
  static ovtest::TempDir dir;
  static const core::Dataset data = [] {
    sim::SimOptions o;
    o.out_dir = dir / "sim";
    o.duration_s = 3.0;
    o.seed = 3;
    o.td.td0_s = 0.02;
    sim::write_simulation(o);
    return core::load_dataset(o.out_dir);
  }();
  return data;
}

/// A feature-level flight (no images: fast).
const core::Dataset &feature_flight() {
  static ovtest::TempDir dir;
  static const core::Dataset data = ovtest::feature_flight(dir / "sim", 6.0, 5, 0.5);
  return data;
}

msckf::VioOptions options(msckf::TdMode mode) {
  msckf::VioOptions o;
  o.td.mode = mode;
  o.init.mode = msckf::InitMode::GroundTruth;
  return o;
}

/// Feeds `data` in the order a live system might receive it: each image 0-80 ms after its stamp, the IMU in bursts
/// 0-30 ms late — so images often arrive before the readings that cover them.
std::vector<StateSample> feed_jittered(const core::Dataset &data, EstimatorSetup setup, unsigned seed) {
  struct Event {
    int64_t arrival;
    bool image;
    size_t index;
  };
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int64_t> image_delay(0, 80000000), imu_delay(0, 30000000);
  std::vector<Event> events;
  int64_t burst = 0;
  for (size_t i = 0; i < data.imu.size(); ++i) {
    if (i % 8 == 0) // a burst of 8 readings arrives together, after the one before
      burst = std::max(burst, data.imu[std::min(i + 7, data.imu.size() - 1)].t_imu_ns + imu_delay(rng));
    events.push_back({burst, false, i});
  }
  int64_t last_image_arrival = 0;
  for (size_t i = 0; i < data.images.size(); ++i) {
    last_image_arrival = std::max(last_image_arrival, data.images[i].t_cam_ns + image_delay(rng));
    events.push_back({last_image_arrival, true, i});
  }
  std::stable_sort(events.begin(), events.end(), [](const Event &a, const Event &b) { return a.arrival < b.arrival; });
  Estimator est(std::move(setup));
  std::vector<StateSample> traj;
  est.add_state_callback([&](const StateSample &s) { traj.push_back(s); });
  for (const Event &e : events) {
    if (!e.image) {
      est.feed_imu(data.imu[e.index]);
      continue;
    }
    const core::ImageEntry &img = data.images[e.index];
    if (img.features)
      est.feed_features(img.t_cam_ns, *img.features);
    else
      est.feed_image(img.t_cam_ns, core::load_gray_image(img, data.cam.width, data.cam.height));
  }
  est.finish();
  return traj;
}

void expect_identical(const std::vector<StateSample> &a, const std::vector<StateSample> &b, const std::string &what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].t_ns, b[i].t_ns) << what << ", state " << i;
    ASSERT_EQ(a[i].p, b[i].p) << what << ", state " << i;
    ASSERT_EQ(a[i].q_WB.coeffs(), b[i].q_WB.coeffs()) << what << ", state " << i;
    ASSERT_EQ(a[i].v, b[i].v) << what << ", state " << i;
    ASSERT_EQ(a[i].td_s, b[i].td_s) << what << ", state " << i;
    ASSERT_EQ(a[i].td_sigma_s, b[i].td_sigma_s) << what << ", state " << i;
  }
}

} // namespace

// The streaming search (holding images until it decides, here at the end of the 3-s flight), the tracker's gyro prior
// (waiting for the IMU over each image) and the filter's IMU hand-over all depend on stamps, never on arrival.
TEST(Estimator, SameTrajectoryWhateverTheThreadsAndTheArrivalOrder) {
  const core::Dataset &d = image_flight();
  for (bool gyro_prior : {false, true}) {
    msckf::VioOptions opt = options(msckf::TdMode::Sr);
    opt.track.gyro_prior = gyro_prior;
    const std::string tag = gyro_prior ? "gyro prior" : "no gyro prior";
    const ovtest::EstimatorRun ref = ovtest::run_estimator(d, opt);
    ASSERT_GT(ref.traj.size(), 40u) << ref.report.init_message;
    ASSERT_TRUE(ref.report.td_search) << "the search did not run: its hand-over was not tested";
    expect_identical(ref.traj, ovtest::run_estimator(d, opt, {}, true).traj, tag + ", threaded");
    for (bool threaded : {false, true}) {
      EstimatorSetup setup = setup_for(d, opt);
      setup.threaded = threaded;
      setup.max_queued_images = 2;
      expect_identical(ref.traj, feed_jittered(d, setup, threaded ? 7 : 8),
                       tag + (threaded ? ", jittered, threaded" : ", jittered"));
    }
  }
}

TEST(Estimator, FeatureLevelRecordingsStreamToo) {
  const core::Dataset &d = feature_flight();
  msckf::VioOptions opt = options(msckf::TdMode::Ton);
  opt.ton.fvon.its.train.max_epochs = opt.ton.fvon.f2f.train.max_epochs = 100;
  const ovtest::EstimatorRun ref = ovtest::run_estimator(d, opt);
  ASSERT_GT(ref.traj.size(), 100u);
  EstimatorSetup setup = setup_for(d, opt);
  setup.threaded = true;
  expect_identical(ref.traj, feed_jittered(d, setup, 3), "ton, jittered, threaded");
}

// A caller that feeds every image before any IMU must not wait forever on a full queue: the stages waiting for the
// IMU never make it wait.
TEST(Estimator, ImagesFarAheadOfTheImuDoNotBlockTheCaller) {
  const core::Dataset &d = feature_flight();
  for (bool search : {false, true}) {
    msckf::VioOptions opt = options(msckf::TdMode::Sr);
    opt.td.search.enabled = search;
    EstimatorSetup setup = setup_for(d, opt);
    setup.threaded = true;
    setup.max_queued_images = 1;
    Estimator est(std::move(setup));
    std::vector<StateSample> traj;
    est.add_state_callback([&](const StateSample &s) { traj.push_back(s); });
    for (const auto &e : d.images)
      est.feed_features(e.t_cam_ns, *e.features);
    for (const auto &m : d.imu)
      est.feed_imu(m);
    est.finish();
    expect_identical(ovtest::run_estimator(d, opt).traj, traj, search ? "search" : "no search");
  }
}

TEST(Estimator, ImagesBeyondTheImuAreSkippedAndCounted) {
  const core::Dataset &d = feature_flight();
  msckf::VioOptions opt = options(msckf::TdMode::Off);
  opt.td.init_s = 0.12; // t_imu = t_cam + 0.12 s: the last images fall beyond the IMU log
  const ovtest::EstimatorRun r = ovtest::run_estimator(d, opt);
  const int64_t last_imu = d.imu.back().t_imu_ns;
  long beyond = 0;
  for (const auto &e : d.images)
    beyond += e.t_cam_ns + 120000000LL > last_imu;
  ASSERT_GT(beyond, 0);
  EXPECT_EQ(r.report.images_skipped, beyond);
  EXPECT_EQ(r.traj.size() + static_cast<size_t>(beyond), d.images.size());
}

TEST(Estimator, PollStatusAndLatency) {
  const core::Dataset &d = feature_flight();
  for (bool threaded : {false, true}) {
    EstimatorSetup setup = setup_for(d, options(msckf::TdMode::Sr));
    setup.threaded = threaded;
    Estimator est(std::move(setup));
    EXPECT_EQ(est.status().phase, EstimatorStatus::Phase::Searching);
    long callbacks = 0;
    est.add_state_callback([&](const StateSample &) { ++callbacks; });
    std::vector<StateSample> polled;
    const PlayResult p = play(d, est, {});
    est.poll(polled);
    const EstimatorStatus st = est.status();
    EXPECT_EQ(st.phase, EstimatorStatus::Phase::Finished);
    EXPECT_TRUE(st.initialized);
    EXPECT_TRUE(st.td_search);
    EXPECT_EQ(static_cast<long>(polled.size()), callbacks);
    EXPECT_EQ(st.states_out, callbacks);
    EXPECT_EQ(st.images_received, static_cast<long>(p.images_fed));
    EXPECT_EQ(st.images_processed + st.images_skipped, st.images_received);
    EXPECT_EQ(st.td_s, polled.back().td_s);
    EXPECT_EQ(est.report().latency_ms.size(), polled.size());
    EXPECT_EQ(est.poll(polled), 0u); // nothing new
  }
}

TEST(Estimator, RefusesFeedsThatCannotBeAStream) {
  const core::Dataset &d = image_flight();
  EstimatorSetup setup = setup_for(d, options(msckf::TdMode::Sr));
  setup.threaded = false;
  Estimator est(setup);
  const cv::Mat gray(d.cam.height, d.cam.width, CV_8UC1, cv::Scalar(0));
  const auto expect_usage = [](const std::function<void()> &f, const std::string &what) {
    try {
      f();
      ADD_FAILURE() << "accepted: " << what;
    } catch (const core::UsageError &e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expect_usage([&] { est.feed_image(1000, cv::Mat(10, 20, CV_8UC1)); }, "20x10");
  expect_usage([&] { est.feed_image(1000, cv::Mat(d.cam.height, d.cam.width, CV_8UC3)); }, "not 8-bit gray");
  est.feed_image(1000, gray);
  expect_usage([&] { est.feed_image(1000, gray); }, "must increase");
  core::ImuData m;
  m.t_imu_ns = 500;
  est.feed_imu(m);
  expect_usage([&] { est.feed_imu(m); }, "increasing time order");
  m.t_imu_ns = 600;
  m.wm.x() = std::numeric_limits<double>::quiet_NaN();
  expect_usage([&] { est.feed_imu(m); }, "not finite");
  est.stop();
  expect_usage([&] { est.feed_image(2000, gray); }, "after finish() or stop()");
  EXPECT_EQ(est.status().phase, EstimatorStatus::Phase::Stopped);
}

// An image stamp near the end of the int64 clock, shifted by t_d, has no IMU-clock time: an error, not a wrap-around.
TEST(Estimator, ImageTimeBeyondTheClockIsAnError) {
  msckf::VioOptions opt = options(msckf::TdMode::Off);
  opt.init.mode = msckf::InitMode::Static;
  opt.td.init_s = 5.0;
  EstimatorSetup setup;
  setup.options = opt;
  setup.camera = feature_flight().cam;
  setup.threaded = false;
  Estimator est(setup);
  const int64_t t = std::numeric_limits<int64_t>::max() - 1000000000LL;
  core::ImuData m;
  m.t_imu_ns = t - 2000000000LL;
  est.feed_imu(m);
  try {
    est.feed_features(t, {});
    est.finish();
    FAIL() << "an overflowing image time was accepted";
  } catch (const core::UsageError &e) {
    EXPECT_NE(std::string(e.what()).find("no IMU-clock time"), std::string::npos) << e.what();
  }
}

TEST(Estimator, NoPoseIsAnErrorNamingTheSourceAndWhy) {
  const core::Dataset &d = feature_flight();
  msckf::VioOptions opt = options(msckf::TdMode::Sr);
  opt.init.mode = msckf::InitMode::Static;
  opt.init.window_s = 30; // longer than the 6-s flight: it never initialises
  EstimatorSetup setup = setup_for(d, opt);
  setup.threaded = true;
  Estimator est(std::move(setup));
  try {
    play(d, est);
    FAIL() << "a run without a pose ended normally";
  } catch (const core::DataError &e) {
    EXPECT_EQ(e.file(), d.root);
    EXPECT_NE(std::string(e.what()).find("no pose was estimated"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("initialisation:"), std::string::npos) << e.what();
  }
}

TEST(Estimator, StopAbandonsWhatWaits) {
  const core::Dataset &d = feature_flight();
  EstimatorSetup setup = setup_for(d, options(msckf::TdMode::Sr));
  setup.threaded = true;
  Estimator est(std::move(setup));
  PlayOptions po;
  po.on_progress = [](size_t i, size_t) { return i < 30; };
  const PlayResult p = play(d, est, po);
  EXPECT_TRUE(p.interrupted);
  EXPECT_EQ(p.images_fed, 30u);
  EXPECT_EQ(est.status().phase, EstimatorStatus::Phase::Stopped);
}
