#include "ov_msckf_ton/init/td_search.h"
#include "ov_core/cam/camera_model.h"
#include "ov_core/io/image_io.h"
#include "ov_core/math/so3.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <unordered_map>

namespace ovton::msckf {

namespace {

/// The fit's filters look this far past the window's last image (the gyro's box filter over an image interval, the
/// refinement around a best candidate at the range's edge), so the IMU must reach it before the window is judged.
constexpr double kImuMarginS = 0.1;
/// IMU before the first image (IMU clock) the search keeps.
constexpr double kImuHistoryS = 60.0;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

} // namespace

std::string TdSearchResult::summary() const {
  char buf[320];
  if (found)
    std::snprintf(buf, sizeof buf,
                  "t_d %.2f +- %.2f ms (searched %.1f +- %.0f ms on images %.1f-%.1f s, %d pairs, RMS angular "
                  "acceleration %.2f rad/s^2, %.1f s)",
                  td_s * 1e3, sigma_s * 1e3, prior_s * 1e3, range_s * 1e3, window_begin_s, window_end_s, pairs,
                  rms_alpha, seconds);
  else
    std::snprintf(buf, sizeof buf, "not used, t_d stays at %.2f ms: %s (%.1f s)", prior_s * 1e3, why.c_str(), seconds);
  return buf;
}

std::string TdSearchResult::caution() const {
  if (!weak_excitation)
    return "";
  // A gentle flight with a realistic IMU pulls t_d confidently off the truth (docs/robustness.md, "Weak excitation").
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "caution: the rotation rate barely changes over the first images (RMS angular acceleration %g "
                "rad/s^2): t_d is weakly observable, its estimate can be pulled by IMU errors the model lacks and its "
                "sigma can be optimistic",
                rms_alpha);
  return buf;
}

TdSearch::TdSearch(const ovton::core::CameraCalib &cam, double prior_td_s, const TdSearchOptions &opt)
    : cam_(cam), prior_s_(prior_td_s), opt_(opt) {
  res_.prior_s = res_.td_s = prior_td_s;
  res_.range_s = opt.range_s;
}

void TdSearch::add_imu(const ovton::core::ImuData &m) {
  if (done_)
    return;
  imu_.push(m);
}

void TdSearch::add_frame(int64_t t_cam_ns, Bearings bearings) {
  if (done_)
    return;
  if (frames_seen_++ == 0)
    t0_ns_ = t_cam_ns;
  frames_.push_back({t_cam_ns, std::move(bearings)});
}

std::pair<size_t, size_t> TdSearch::window(double start_s) const {
  const auto at_or_after = [&](double s) {
    return static_cast<size_t>(
        std::find_if(frames_.begin(), frames_.end(), [&](const Frame &f) { return rel_s(f.t_cam_ns) >= s; }) -
        frames_.begin());
  };
  return {at_or_after(start_s), at_or_after(start_s + opt_.window_s)};
}

bool TdSearch::must_decide_before(int64_t t_cam_ns) const {
  return !done_ && frames_seen_ > 0 && rel_s(t_cam_ns) >= start_s_ + opt_.window_s;
}

int64_t TdSearch::imu_needed_ns() const {
  const int64_t last = frames_.empty() ? t0_ns_ : frames_.back().t_cam_ns;
  return ovton::core::saturating_add_ns(last, ovton::core::s_to_ns(prior_s_ + opt_.range_s + kImuMarginS));
}

bool TdSearch::decide(bool end_of_stream) {
  if (done_)
    return true;
  const auto t_start = std::chrono::steady_clock::now();
  // What the IMU said a minute before the first image is of no use (the judged time is what the readings' running
  // integral starts from, so the same readings are kept whenever they were handed over).
  if (frames_seen_ > 0)
    imu_.drop_before(ovton::core::saturating_add_ns(t0_ns_, ovton::core::s_to_ns(prior_s_ - kImuHistoryS)));
  if (end_of_stream && (frames_seen_ < 3 || imu_.size() < 3)) {
    res_.why = "too few images or IMU readings";
    done_ = true;
  } else if (frames_seen_ > 0) {
    const auto [b, e] = window(start_s_);
    std::vector<double> t_img(frames_.size());
    for (size_t i = 0; i < frames_.size(); ++i)
      t_img[i] = rel_s(frames_[i].t_cam_ns);
    const double rms = rms_alpha(t_img, b, e, ovton::core::GyroIntegral(imu_, t0_ns_), prior_s_);
    if (rms > best_rms_) {
      best_rms_ = rms;
      best_images_ = e - b;
      best_begin_s_ = b < e ? t_img[b] : 0.0;
      best_end_s_ = b < e ? t_img[e - 1] : 0.0;
    }
    if (rms >= opt_.min_rms_alpha) {
      conclude(end_of_stream);
    } else if (end_of_stream || start_s_ + 1.0 > opt_.max_start_s) {
      conclude(end_of_stream); // the window that changed most is all there is
    } else {
      // The next window starts a second later: the images before it are of no further use.
      start_s_ += 1.0;
      while (!frames_.empty() && rel_s(frames_.front().t_cam_ns) < start_s_)
        frames_.pop_front();
    }
  } else if (end_of_stream) {
    res_.why = "too few images or IMU readings";
    done_ = true;
  }
  compute_s_ += seconds_since(t_start);
  res_.seconds = compute_s_;
  if (done_) {
    frames_.clear();
    imu_ = ovton::core::ImuBuffer();
  }
  return done_;
}

void TdSearch::conclude(bool end_of_stream) {
  (void)end_of_stream;
  done_ = true;
  res_.rms_alpha = std::max(0.0, best_rms_);
  if (best_images_ <= 2) {
    res_.why = "no stretch of images within the IMU log";
    return;
  }
  res_.window_begin_s = best_begin_s_;
  res_.window_end_s = best_end_s_;
  if (best_rms_ < opt_.min_rms_alpha) {
    res_.weak_excitation = true;
    char why[160];
    std::snprintf(why, sizeof why, "too little rotation change (RMS angular acceleration %.2f rad/s^2 < %.2f)",
                  best_rms_, opt_.min_rms_alpha);
    res_.why = why;
    return;
  }
  // A window that qualifies is the current one: its images are the kept ones.
  const auto [b, e] = window(start_s_);
  fit_offset(pair_rates(b, e), imu_, t0_ns_, prior_s_, opt_, res_);
}

std::vector<PairRate> TdSearch::pair_rates(size_t b, size_t e) const {
  const Eigen::Matrix3d R_BC = cam_.T_BC.block<3, 3>(0, 0);
  const double huber_rad = 2.0 / std::max(cam_.intrinsics(0), cam_.intrinsics(1));
  // Bearings matched by id through hash maps filled in the tracker's order, as consecutive images are compared.
  std::unordered_map<size_t, Eigen::Vector3d> prev, curr;
  std::vector<PairRate> pairs;
  std::vector<Eigen::Vector3d> bear0, bear1;
  for (size_t i = b; i < e; ++i) {
    curr.clear();
    for (const auto &[id, bearing] : frames_[i].bearings)
      curr[id] = bearing;
    if (i > b) {
      bear0.clear();
      bear1.clear();
      for (const auto &[id, b1] : curr)
        if (auto it = prev.find(id); it != prev.end()) {
          bear0.push_back(it->second);
          bear1.push_back(b1);
        }
      const double t0 = rel_s(frames_[i - 1].t_cam_ns), t1 = rel_s(frames_[i].t_cam_ns), dt = t1 - t0;
      if (bear0.size() >= 10 && dt > 0) {
        // bear0 ≈ R_{C_{k-1} C_k}·bear1; the body rotation over the interval is R_BC·R·R_CB, so its rate is
        // R_BC·log(R)/dt.
        const Eigen::Matrix3d R = fit_rotation(bear0, bear1, huber_rad);
        pairs.push_back({t0, t1, R_BC * ovton::core::so3_log(R) / dt});
      }
    }
    std::swap(prev, curr);
  }
  return pairs;
}

TdSearch::Bearings bearings_of(const std::vector<ovton::core::TrackedFeature> &features) {
  TdSearch::Bearings out;
  out.reserve(features.size());
  for (const auto &f : features)
    out.emplace_back(f.id, f.xy.homogeneous().normalized());
  return out;
}

TdSearchResult search_td(const std::vector<ovton::core::ImageEntry> &images,
                         const std::vector<ovton::core::ImuData> &imu, const ovton::core::CameraCalib &cam,
                         double prior_td_s, const TdSearchOptions &opt, const ovton::core::TrackKLTOptions &track,
                         std::shared_ptr<const ovton::core::GyroRotationPrior> rotation_prior,
                         const TdSearchImageLoader &load) {
  const auto t_start = std::chrono::steady_clock::now();
  TdSearch search(cam, prior_td_s, opt);
  size_t k = 0; // IMU readings handed over
  const auto imu_past = [&](int64_t t_imu_ns) {
    while (k < imu.size() && (k == 0 || imu[k - 1].t_imu_ns <= t_imu_ns))
      search.add_imu(imu[k++]);
  };
  const ovton::core::CameraModel camera(cam);
  std::unique_ptr<ovton::core::TrackKLT> tracker;
  for (const auto &e : images) {
    while (search.must_decide_before(e.t_cam_ns)) {
      imu_past(search.imu_needed_ns());
      if (search.decide(false))
        break;
    }
    if (search.done())
      break;
    TdSearch::Bearings bearings;
    if (e.features) {
      for (const auto &o : *e.features)
        bearings.emplace_back(o.id, camera.undistort(o.uv).homogeneous().normalized());
    } else {
      if (!tracker) {
        tracker = std::make_unique<ovton::core::TrackKLT>(camera, track);
        tracker->set_rotation_prior(rotation_prior);
      }
      const cv::Mat img = load ? load(e) : ovton::core::load_gray_image(e, cam.width, cam.height);
      bearings = bearings_of(tracker->track(e.t_cam_ns, img));
    }
    search.add_frame(e.t_cam_ns, std::move(bearings));
  }
  imu_past(std::numeric_limits<int64_t>::max());
  while (!search.decide(true)) {
  }
  TdSearchResult r = search.result();
  r.seconds = seconds_since(t_start);
  return r;
}

} // namespace ovton::msckf
