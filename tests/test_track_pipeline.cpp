// TrackPipeline: images tracked on a thread of their own are tracked exactly as one tracker on the caller's thread
// tracks them, whatever the consumer skips; errors reach the consumer with the image that caused them; and a filter
// fed through it writes the same trajectory as one that tracks itself.
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_io.h"
#include "ov_core/io/image_prefetcher.h"
#include "ov_core/io/replay.h"
#include "ov_core/track/track_pipeline.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_sim/simulator.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <stdexcept>

using namespace ovton::core;

namespace {

/// A short rendered flight (images, IMU, ground truth), written once for the tests below.
const Dataset &flight() {
  static ovtest::TempDir dir;
  static const Dataset data = [] {
    ovton::sim::SimOptions o;
    o.out_dir = dir / "sim";
    o.duration_s = 3.0;
    o.seed = 3;
    ovton::sim::write_simulation(o);
    return load_dataset(o.out_dir);
  }();
  return data;
}

TrackPipeline::ImageGetter decoder(const Dataset &d) {
  return [&d](size_t i) { return load_gray_image(d.images[i], d.cam.width, d.cam.height); };
}

/// What one tracker on this thread outputs for every image of the list.
std::vector<std::vector<TrackedFeature>> sequential(const Dataset &d) {
  TrackKLT tracker(CameraModel(d.cam), TrackKLTOptions{});
  std::vector<std::vector<TrackedFeature>> out;
  for (const auto &e : d.images)
    out.push_back(tracker.track(e.t_cam_ns, load_gray_image(e, d.cam.width, d.cam.height)));
  return out;
}

void expect_same(const std::vector<TrackedFeature> &a, const std::vector<TrackedFeature> &b, size_t index) {
  ASSERT_EQ(a.size(), b.size()) << "image " << index;
  for (size_t j = 0; j < a.size(); ++j) {
    EXPECT_EQ(a[j].id, b[j].id) << "image " << index;
    EXPECT_EQ(a[j].uv, b[j].uv) << "image " << index;
    EXPECT_EQ(a[j].xy, b[j].xy) << "image " << index;
  }
}

} // namespace

TEST(TrackPipeline, TracksAsOneTrackerDoesWhateverIsSkipped) {
  const Dataset &d = flight();
  const auto want = sequential(d);
  ASSERT_GT(want.size(), 40u);
  ASSERT_GT(want.back().size(), 50u) << "the flight has too few features to test anything";
  for (size_t ahead : {1u, 3u}) {
    TrackPipeline p(d.images, CameraModel(d.cam), TrackKLTOptions{}, decoder(d), ahead);
    for (size_t i = 0; i < d.images.size(); ++i) {
      if (i >= 10 && i < 17)
        continue; // skipped by the consumer: the thread still tracks through them
      const TrackedFrame f = p.take(d.images[i]);
      EXPECT_FALSE(f.error);
      expect_same(f.features, want[i], i);
    }
  }
}

// The coarse t_d search's tracks of the first images and its tracker, handed over: the rest is tracked as one
// tracker tracks everything, on the pipeline's thread or on the caller's.
TEST(TrackPipeline, GoesOnFromAGivenStart) {
  const Dataset &d = flight();
  const auto want = sequential(d);
  for (bool threaded : {false, true}) {
    TrackedStart start;
    start.tracker = std::make_unique<TrackKLT>(CameraModel(d.cam), TrackKLTOptions{});
    for (size_t i = 0; i < 20; ++i)
      start.frames.push_back(
          start.tracker->track(d.images[i].t_cam_ns, load_gray_image(d.images[i], d.cam.width, d.cam.height)));
    size_t asked = 0;
    TrackPipeline p(
        d.images, std::move(start),
        [&](size_t i) {
          ++asked;
          EXPECT_GE(i, 20u) << "a given image was decoded";
          return load_gray_image(d.images[i], d.cam.width, d.cam.height);
        },
        threaded);
    for (size_t i = 0; i < d.images.size(); ++i) {
      if (i == 5 || (i >= 30 && i < 33))
        continue; // skipped, among the given ones and after them
      const TrackedFrame f = p.take(i);
      EXPECT_EQ(f.on_caller_thread, !threaded || i < 20);
      expect_same(f.features, want[i], i);
    }
    EXPECT_EQ(asked, d.images.size() - 20);
  }
}

// A clone goes on as the original does, whichever is fed first: it shares no pixels with it.
TEST(TrackPipeline, ClonedTrackerGoesOnAsTheOriginal) {
  const Dataset &d = flight();
  const auto want = sequential(d);
  const auto image = [&](size_t i) { return load_gray_image(d.images[i], d.cam.width, d.cam.height); };
  for (bool original_first : {true, false}) {
    TrackKLT a(CameraModel(d.cam), TrackKLTOptions{});
    for (size_t i = 0; i < 15; ++i)
      a.track(d.images[i].t_cam_ns, image(i));
    const auto b = a.clone();
    std::vector<std::vector<TrackedFeature>> out_a, out_b;
    TrackKLT &first = original_first ? a : *b, &second = original_first ? *b : a;
    auto &out_first = original_first ? out_a : out_b, &out_second = original_first ? out_b : out_a;
    for (size_t i = 15; i < d.images.size(); ++i)
      out_first.push_back(first.track(d.images[i].t_cam_ns, image(i)));
    for (size_t i = 15; i < d.images.size(); ++i)
      out_second.push_back(second.track(d.images[i].t_cam_ns, image(i)));
    for (size_t i = 15; i < d.images.size(); ++i) {
      expect_same(out_a[i - 15], want[i], i);
      expect_same(out_b[i - 15], want[i], i);
    }
  }
}

TEST(TrackPipeline, ErrorsReachTheConsumerWithTheirImage) {
  const Dataset &d = flight();
  const auto want = sequential(d);
  const size_t bad = 12;
  const auto getter = [&d, bad](size_t i) {
    return i == bad ? cv::Mat() : load_gray_image(d.images[i], d.cam.width, d.cam.height);
  };
  {
    TrackPipeline p(d.images, CameraModel(d.cam), TrackKLTOptions{}, getter);
    for (size_t i = 0; i < bad; ++i)
      expect_same(p.take(i).features, want[i], i);
    try {
      p.take(bad);
      ADD_FAILURE() << "an unreadable image was tracked";
    } catch (const DataError &e) {
      EXPECT_NE(std::string(e.what()).find(d.images[bad].path), std::string::npos) << e.what();
    }
    EXPECT_THROW(p.take(bad + 1), DataError) << "tracking must not jump the unreadable image";
  }
  {
    // A consumer that skipped the unreadable image gets its error at the next image it asks for.
    TrackPipeline p(d.images, CameraModel(d.cam), TrackKLTOptions{}, getter);
    EXPECT_THROW(p.take(bad + 3), DataError);
  }
  {
    // What the getter throws (a wrong size, a corrupt bag message) is handed over the same way.
    TrackPipeline p(d.images, CameraModel(d.cam), TrackKLTOptions{}, [&](size_t i) -> cv::Mat {
      if (i == 2)
        throw DataError(d.images[i].path, "test error");
      return load_gray_image(d.images[i], d.cam.width, d.cam.height);
    });
    EXPECT_NO_THROW(p.take(0));
    EXPECT_THROW(p.take(2), DataError);
  }
}

TEST(TrackPipeline, RefusesIndicesThatDoNotIncrease) {
  const Dataset &d = flight();
  TrackPipeline p(d.images, CameraModel(d.cam), TrackKLTOptions{}, decoder(d));
  p.take(3);
  EXPECT_THROW(p.take(3), std::logic_error);
  EXPECT_THROW(p.take(1), std::logic_error);
  EXPECT_THROW(p.take(d.images.size()), std::logic_error);
  const ImageEntry other = d.images[5]; // a copy: not an entry of the pipeline's list
  EXPECT_THROW(p.take(other), std::logic_error);
  EXPECT_NO_THROW(p.take(4));
}

TEST(TrackPipeline, StopsCleanlyWhenDroppedEarly) {
  const Dataset &d = flight();
  for (size_t stop_after : {0u, 1u, 10u}) {
    TrackPipeline p(d.images, CameraModel(d.cam), TrackKLTOptions{}, decoder(d), 2);
    for (size_t i = 0; i < stop_after; ++i)
      EXPECT_FALSE(p.take(i).features.empty());
  } // the destructor joins a thread that may be waiting or tracking
}

// The whole filter: decoding on a thread of its own (the image source), and tracking on another drawing from it (as
// `ovton run` does), give the trajectory of a filter that decodes and tracks on its own thread.
TEST(TrackPipeline, FilterGivesTheSameTrajectoryOnAnyThreads) {
  const Dataset &d = flight();
  ovton::msckf::VioOptions opt;
  opt.td.mode = ovton::msckf::TdMode::Sr;
  opt.init.mode = ovton::msckf::InitMode::GroundTruth;
  enum Threads { kOne, kDecoding, kDecodingAndTracking };
  const auto run = [&](Threads threads) {
    ovton::msckf::VioManager vio(opt, d.cam, d.imu_calib);
    vio.set_groundtruth(d.groundtruth);
    std::vector<StateSample> traj;
    vio.set_state_callback([&](const StateSample &s) { traj.push_back(s); });
    std::unique_ptr<ImagePrefetcher> pf;
    std::unique_ptr<TrackPipeline> tp;
    if (threads != kOne) {
      pf = std::make_unique<ImagePrefetcher>(d.images);
      vio.set_image_source([&](const ImageEntry &e) { return pf->get(e); });
    }
    if (threads == kDecodingAndTracking) {
      tp = std::make_unique<TrackPipeline>(d.images, CameraModel(d.cam), opt.track,
                                           [&](size_t i) { return pf->get(i); });
      vio.set_frame_source([&](const ImageEntry &e) { return tp->take(e); });
    }
    Replay(d).run(vio);
    EXPECT_EQ(vio.times().tracking_thread > 0, threads == kDecodingAndTracking);
    return traj;
  };
  const auto a = run(kOne);
  ASSERT_GT(a.size(), 40u);
  for (Threads threads : {kDecoding, kDecodingAndTracking}) {
    const auto b = run(threads);
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].t_ns, b[i].t_ns);
      EXPECT_EQ((a[i].p - b[i].p).norm(), 0.0) << "pose " << i << ", threads " << threads;
      EXPECT_EQ(a[i].q_WB.coeffs(), b[i].q_WB.coeffs()) << "pose " << i << ", threads " << threads;
      EXPECT_EQ(a[i].td_s, b[i].td_s) << "pose " << i << ", threads " << threads;
    }
  }
}
