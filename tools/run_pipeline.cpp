#include "tools/run_pipeline.h"
#include "ov_core/io/image_io.h"
#include "ov_core/io/image_prefetcher.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/track/track_pipeline.h"
#include "ov_core/types/errors.h"
#include "tools/progress.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>

namespace ovton::cli {

void apply_dataset_defaults(const ovton::core::Dataset &data, bool td_init_given, ovton::msckf::VioOptions &opt) {
  if (!td_init_given && data.td_prior_s != 0.0)
    opt.td.init_s = data.td_prior_s;
}

std::shared_ptr<const ovton::core::GyroRotationPrior> make_rotation_prior(const ovton::core::Dataset &data,
                                                                          const ovton::msckf::VioOptions &opt) {
  if (!opt.track.gyro_prior || data.imu.size() < 2)
    return nullptr;
  const Eigen::Matrix3d R_IC = data.imu_calib.T_BI.block<3, 3>(0, 0).transpose() * data.cam.T_BC.block<3, 3>(0, 0);
  return std::make_shared<ovton::core::GyroRotationPrior>(data.imu, R_IC, opt.td.init_s);
}

std::optional<ovton::msckf::TdSearchResult> run_td_search(const ovton::core::Dataset &data,
                                                          ovton::msckf::VioOptions &opt,
                                                          ovton::core::DecodedImages *keep, size_t keep_bytes,
                                                          ovton::core::TrackedStart *tracked) {
  using ovton::msckf::TdMode;
  const bool due = opt.td.search.enabled && opt.td.mode != TdMode::Off && opt.td.mode != TdMode::Oracle;
  opt.td.search.enabled = false;
  if (!due)
    return std::nullopt;
  // The LK starting points at the prior offset: the search has not found its own yet.
  const auto rotation_prior = make_rotation_prior(data, opt);
  size_t kept_bytes = 0;
  bool first_load = true, keeping = keep != nullptr;
  const auto load = [&](const ovton::core::ImageEntry &e) {
    cv::Mat img = ovton::core::load_gray_image(e, data.cam.width, data.cam.height);
    const auto index = ovton::core::entry_index(data.images, e);
    // A search that starts loading at the first image has its window there and hands its tracks over (search_td):
    // the filter then needs none of these images, and keeping them would only hold their memory.
    if (first_load && tracked && index == size_t{0})
      keeping = false;
    first_load = false;
    const size_t bytes = img.total() * img.elemSize();
    if (keeping && index && kept_bytes + bytes <= keep_bytes) {
      (*keep)[*index] = img;
      kept_bytes += bytes;
    }
    return img;
  };
  const auto r = ovton::msckf::search_td(data.images, data.imu, data.cam, opt.td.init_s, opt.td.search, opt.track,
                                         rotation_prior, load, tracked);
  if (r.found) {
    opt.td.init_s = r.td_s;
    // The filter's prior must cover the search's own error.
    opt.td.sigma_init_s = std::max(opt.td.sigma_init_s, 3 * r.sigma_s);
  }
  return r;
}

RunResult run_dataset(const ovton::core::Dataset &data, const RunRequest &req) {
  ovton::msckf::VioOptions opt = req.opt;
  RunResult res;
  std::shared_ptr<const ovton::core::DecodedImages> decoded = req.decoded;
  ovton::core::TrackedStart tracked; // the search's tracks, when the filter can go on from them
  if (req.tracked && req.tracked->tracker) {
    tracked.frames = req.tracked->frames;
    tracked.tracker = req.tracked->tracker->clone();
  }
  if (decoded || req.tracked)
    res.td_search = run_td_search(data, opt);
  else {
    auto kept = std::make_shared<ovton::core::DecodedImages>();
    res.td_search = run_td_search(data, opt, kept.get(), req.keep_search_images_bytes,
                                  req.reuse_search_tracks ? &tracked : nullptr);
    if (!kept->empty())
      decoded = std::move(kept);
  }
  res.images_predecoded = decoded ? decoded->size() : 0;
  if (res.td_search && req.progress) // before the run, so that it is seen even when the run fails
    std::fprintf(stderr, "coarse t_d search: %s\n", res.td_search->summary().c_str());
  ovton::msckf::VioManager vio(opt, data.cam, data.imu_calib);
  const auto prior = make_rotation_prior(data, opt);
  vio.set_rotation_prior(prior);
  if (data.has_td_truth())
    vio.set_td_oracle([&data](int64_t t) { return data.td_truth_at(t); });
  else if (opt.td.mode == ovton::msckf::TdMode::Oracle)
    throw ovton::core::UsageError("mode oracle needs " + data.root + " to have td_truth/data.csv");
  std::unique_ptr<ovton::eval::NeesAccumulator> nees;
  if (opt.init.mode == ovton::msckf::InitMode::GroundTruth) {
    if (!data.has_groundtruth() || !data.groundtruth.front().has_velocity)
      throw ovton::core::UsageError("ground-truth initialisation needs full-state ground truth in " + data.root);
    vio.set_groundtruth(data.groundtruth);
    nees = std::make_unique<ovton::eval::NeesAccumulator>(data.groundtruth, data.td_truth);
  }
  std::unique_ptr<ovton::core::TrajectoryWriter> writer;
  if (!req.output.empty())
    writer = std::make_unique<ovton::core::TrajectoryWriter>(req.output, req.tum ? ovton::core::TrajectoryFormat::Tum
                                                                                 : ovton::core::TrajectoryFormat::Csv);
  vio.set_state_callback([&](const ovton::core::StateSample &s) {
    if (writer)
      writer->write(s);
    if (nees)
      nees->add(s);
    res.traj.push_back(s);
  });
  std::unique_ptr<ovton::msckf::ResidualLogWriter> rlog;
  if (!req.residual_log.empty()) {
    rlog = std::make_unique<ovton::msckf::ResidualLogWriter>(req.residual_log);
    vio.set_residual_log(rlog.get());
  }
  std::unique_ptr<ovton::core::VelocityLogWriter> vlog;
  if (!req.velocity_log.empty()) {
    vlog = std::make_unique<ovton::core::VelocityLogWriter>(req.velocity_log);
    vio.set_velocity_log(vlog.get());
  }

  std::unique_ptr<ovton::core::ImagePrefetcher> prefetcher;
  if (req.prefetch && !data.images.empty() && !data.images.front().features)
    prefetcher = std::make_unique<ovton::core::ImagePrefetcher>(data.images, 2, decoded);
  // An image of the wrong size is reported with its file here, not as a tracker error without one.
  const auto image_of = [&prefetcher, &data, &decoded](const ovton::core::ImageEntry &e) {
    if (!prefetcher) {
      if (const auto index = decoded ? ovton::core::entry_index(data.images, e) : std::nullopt)
        if (const auto it = decoded->find(*index); it != decoded->end())
          return it->second; // checked when the search decoded it
      return ovton::core::load_gray_image(e, data.cam.width, data.cam.height);
    }
    cv::Mat img = prefetcher->get(e);
    ovton::core::check_gray_image(img, e, data.cam.width, data.cam.height);
    return img;
  };
  // Tracking on a thread of its own, and/or going on from the search's tracks; else the filter tracks the images
  // itself. Declared after the prefetcher it draws from, so that it stops first.
  std::unique_ptr<ovton::core::TrackPipeline> pipeline;
  const bool threaded = prefetcher && req.track_thread;
  if (threaded || tracked.tracker) {
    if (!tracked.tracker)
      tracked.tracker = std::make_unique<ovton::core::TrackKLT>(ovton::core::CameraModel(data.cam), opt.track);
    tracked.tracker->set_rotation_prior(prior); // at the offset the search found
    res.images_pretracked = tracked.frames.size();
    pipeline = std::make_unique<ovton::core::TrackPipeline>(
        data.images, std::move(tracked), [&image_of, &data](size_t i) { return image_of(data.images[i]); }, threaded);
    vio.set_frame_source([&pipeline](const ovton::core::ImageEntry &e) { return pipeline->take(e); });
  } else {
    vio.set_image_source(image_of);
  }
  ProgressBar bar(req.label.empty() ? "run " + ovton::msckf::to_string(opt.td.mode) : req.label, !req.progress);
  const auto t0 = std::chrono::steady_clock::now();
  size_t last_i = 0;
  res.replay = ovton::core::Replay(data).run(vio, [&](size_t i, size_t n) {
    last_i = i;
    char extra[64];
    std::snprintf(extra, sizeof(extra), "t_d %.3f ms", vio.state().td * 1e3);
    bar.update(i, n, extra);
    if (req.on_progress)
      req.on_progress(i, n);
    return !interrupted() && (req.max_images <= 0 || static_cast<long>(i) < req.max_images);
  });
  bar.finish();
  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  res.interrupted = interrupted();
  if (last_i > 0)
    res.data_span_s = ovton::core::ns_to_s(data.images[last_i - 1].t_cam_ns - data.images.front().t_cam_ns);
  res.counters = vio.counters();
  res.times = vio.times();
  if (nees)
    res.nees = nees->stats();
  res.init_message = vio.init_message();
  res.acceptance = vio.health().total();
  // A header-only trajectory is not a result: say why nothing was estimated.
  if (res.traj.empty() && !res.interrupted)
    throw ovton::core::DataError(data.root, "no pose was estimated from " + std::to_string(res.replay.images_fed) +
                                                " images (" + std::to_string(res.replay.images_skipped) +
                                                " beyond the IMU log); initialisation: " + res.init_message);
  return res;
}

} // namespace ovton::cli
