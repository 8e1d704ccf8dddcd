#include "ov_msckf_ton/estimator/dataset_player.h"
#include "ov_core/io/image_io.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <thread>

namespace ovton {

void apply_dataset_defaults(const core::Dataset &data, bool td_init_given, msckf::VioOptions &opt) {
  if (!td_init_given && data.td_prior_s != 0.0)
    opt.td.init_s = data.td_prior_s;
}

EstimatorSetup setup_for(const core::Dataset &data, const msckf::VioOptions &opt) {
  EstimatorSetup s;
  s.options = opt;
  s.camera = data.cam;
  const size_t n_cams = opt.rig.max_cameras > 0 ? static_cast<size_t>(opt.rig.max_cameras) : data.num_cameras();
  for (size_t k = 1; k < std::min(n_cams, data.num_cameras()); ++k)
    s.more_cameras.push_back(data.more_cameras[k - 1].cam);
  s.imu = data.imu_calib;
  s.source = data.root;
  if (opt.init.mode == msckf::InitMode::GroundTruth)
    s.aids.groundtruth = data.groundtruth;
  if (data.has_td_truth())
    s.aids.td_truth = [&data](int64_t t_cam_ns) { return data.td_truth_at(t_cam_ns); };
  return s;
}

std::shared_ptr<const core::GyroRotationPrior> rotation_prior_for(const core::Dataset &data,
                                                                  const msckf::VioOptions &opt) {
  if (!opt.track.gyro_prior || data.imu.size() < 2)
    return nullptr;
  return std::make_shared<core::GyroRotationPrior>(data.imu, core::camera_to_imu_rotation(data.cam, data.imu_calib),
                                                   opt.td.init_s);
}

PlayResult play(const core::Dataset &data, Estimator &est, const PlayOptions &opt) {
  using Clock = std::chrono::steady_clock;
  const auto ms_since = [](Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  };
  PlayResult res;
  const auto wall0 = Clock::now();
  const size_t n = data.images.size();
  const size_t n_feed = opt.max_images > 0 ? std::min(n, static_cast<size_t>(opt.max_images)) : n;
  // With a pace, a message is fed when its stamp is due (the first one's stamp is now).
  const int64_t t_first = std::min(data.images.empty() ? INT64_MAX : data.images.front().t_cam_ns,
                                   data.imu.empty() ? INT64_MAX : data.imu.front().t_imu_ns);
  const auto wait_for = [&](int64_t t_ns) {
    if (opt.pace > 0)
      std::this_thread::sleep_until(
          wall0 + std::chrono::nanoseconds(static_cast<int64_t>(static_cast<double>(t_ns - t_first) / opt.pace)));
  };
  // A rig's further cameras: the image with the primary's stamp (cameras triggered together share it), if any.
  const size_t n_more = est.camera_count() - 1;
  std::vector<size_t> next_more(n_more, 0);
  std::vector<cv::Mat> grays(1 + n_more);
  size_t k = 0; // next IMU reading
  const auto feed_imu_to = [&](int64_t t_ns) {
    for (; k < data.imu.size() && data.imu[k].t_imu_ns <= t_ns; ++k) {
      wait_for(data.imu[k].t_imu_ns);
      est.feed_imu(data.imu[k]);
    }
  };
  for (size_t i = 0; i < n_feed; ++i) {
    const core::ImageEntry &e = data.images[i];
    feed_imu_to(e.t_cam_ns);
    wait_for(e.t_cam_ns);
    if (e.features) {
      est.feed_features(e.t_cam_ns, *e.features);
    } else {
      const auto t0 = Clock::now();
      const cv::Mat gray = core::load_gray_image(e, data.cam.width, data.cam.height);
      if (n_more == 0) {
        res.decode_ms += ms_since(t0);
        est.feed_image(e.t_cam_ns, gray);
      } else {
        grays[0] = gray;
        for (size_t c = 0; c < n_more; ++c) {
          const core::CameraStream &cs = data.more_cameras[c];
          size_t &j = next_more[c];
          while (j < cs.images.size() && cs.images[j].t_cam_ns < e.t_cam_ns)
            ++j;
          grays[c + 1] = j < cs.images.size() && cs.images[j].t_cam_ns == e.t_cam_ns
                             ? core::load_gray_image(cs.images[j], cs.cam.width, cs.cam.height)
                             : cv::Mat();
        }
        res.decode_ms += ms_since(t0);
        est.feed_images(e.t_cam_ns, grays);
      }
    }
    res.images_fed = i + 1;
    if (opt.on_progress && !opt.on_progress(i + 1, n)) {
      res.interrupted = true;
      break;
    }
  }
  if (res.images_fed > 0)
    res.data_span_s = core::ns_to_s(data.images[res.images_fed - 1].t_cam_ns - data.images.front().t_cam_ns);
  if (res.interrupted) {
    est.stop();
  } else {
    feed_imu_to(n_feed < n && n_feed > 0 ? data.images[n_feed - 1].t_cam_ns + core::s_to_ns(12.0)
                                         : std::numeric_limits<int64_t>::max());
    est.finish();
    // A recording cut short: the states up to the cut are out; now the cut is an error (naming the file and byte).
    // With max_images short of the recording the cut was never reached.
    if (n_feed == n)
      core::check_not_truncated(data);
  }
  res.imu_fed = k;
  res.wall_s = std::chrono::duration<double>(Clock::now() - wall0).count();
  return res;
}

} // namespace ovton
