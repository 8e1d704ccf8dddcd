#include "ov_eval/trackstats.h"
#include "ov_core/io/image_codecs.h"
#include "ov_core/types/errors.h"
#include "ov_eval/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <sstream>

namespace ovton::eval {

namespace {

template <typename T> double quantile(std::vector<T> v, double q) {
  if (v.empty())
    return 0.0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return static_cast<double>(v[k]);
}

void check_options(const TrackStatsOptions &o) {
  if (o.max_points < 1 || o.win_size < 3 || o.pyr_levels < 1 || !(o.fb_max_px > 0) || !(o.mask_radius_px >= 0) ||
      !(o.gftt_quality > 0 && o.gftt_quality < 1) || o.gftt_block < 3 || !(o.low_gradient > 0))
    throw ovton::core::UsageError("trackstats: options out of range (points >= 1, window >= 3, levels >= 1, "
                                  "positive thresholds, quality in (0,1), block >= 3)");
  if (o.t_end_ns < o.t_begin_ns)
    throw ovton::core::UsageError("trackstats: the span ends before it begins");
}

/// The tracker loop over n images fetched by `image(i)` (stamp, 8-bit grey).
TrackStatsResult run(size_t n, const std::function<int64_t(size_t)> &stamp, const std::function<cv::Mat(size_t)> &image,
                     const TrackStatsOptions &opt) {
  check_options(opt);
  TrackStatsResult res;
  std::vector<cv::Point2f> pts;
  std::vector<int> age;
  std::vector<cv::Mat> prev_pyr;
  const cv::Size win(opt.win_size, opt.win_size);
  const int max_level = opt.pyr_levels - 1;
  const cv::TermCriteria tc(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
  size_t used = 0;
  for (size_t i = 0; i < n; ++i) {
    const int64_t t = stamp(i);
    if (t < opt.t_begin_ns || t > opt.t_end_ns)
      continue;
    const cv::Mat img = image(i);
    ++used;
    FrameTrackStats fs;
    fs.t_cam_ns = t;
    std::vector<cv::Mat> pyr;
    cv::buildOpticalFlowPyramid(img, pyr, win, max_level);
    std::vector<double> fb_frame;
    if (!pts.empty()) {
      std::vector<cv::Point2f> next, back;
      std::vector<uchar> st, st2;
      std::vector<float> err;
      cv::calcOpticalFlowPyrLK(prev_pyr, pyr, pts, next, st, err, win, max_level, tc);
      cv::calcOpticalFlowPyrLK(pyr, prev_pyr, next, back, st2, err, win, max_level, tc);
      std::vector<cv::Point2f> kept;
      std::vector<int> kept_age;
      for (size_t k = 0; k < pts.size(); ++k) {
        bool ok = st[k] && st2[k];
        if (ok) {
          const double fb = cv::norm(back[k] - pts[k]);
          fb_frame.push_back(fb);
          res.fb_errors.push_back(fb);
          ok = fb < opt.fb_max_px && next[k].x >= 0 && next[k].y >= 0 && next[k].x <= img.cols - 1 &&
               next[k].y <= img.rows - 1;
        }
        if (ok) {
          kept.push_back(next[k]);
          kept_age.push_back(age[k] + 1);
        } else if (age[k] >= 2) {
          res.track_lengths.push_back(age[k]);
        } else {
          ++res.summary.lost_at_once;
        }
      }
      pts.swap(kept);
      age.swap(kept_age);
    }
    fs.tracked = static_cast<int>(pts.size());
    if (fs.tracked < opt.max_points) {
      cv::Mat mask(img.size(), CV_8U, cv::Scalar(255));
      for (const auto &p : pts)
        cv::circle(mask, p, static_cast<int>(std::lround(opt.mask_radius_px)), cv::Scalar(0), cv::FILLED);
      std::vector<cv::Point2f> fresh;
      cv::goodFeaturesToTrack(img, fresh, opt.max_points - fs.tracked, opt.gftt_quality, opt.mask_radius_px, mask,
                              opt.gftt_block);
      for (const auto &p : fresh) {
        pts.push_back(p);
        age.push_back(1);
      }
      fs.detected = static_cast<int>(fresh.size());
    }
    const int total = fs.tracked + fs.detected;
    fs.new_share = total > 0 ? static_cast<double>(fs.detected) / total : 0.0;
    fs.fb_median_px = quantile(fb_frame, 0.5);
    const GradientStats g = gradient_stats(img, opt.low_gradient);
    fs.low_gradient_share = g.low_share;
    fs.gradient_median = g.median;
    fs.noise_sigma = g.noise_sigma;
    fs.mean_intensity = g.mean_intensity;
    res.frames.push_back(fs);
    prev_pyr = std::move(pyr);
  }
  if (used < 2)
    throw ovton::core::UsageError("trackstats: fewer than 2 images in the span");
  for (int a : age)
    if (a >= 2) {
      res.track_lengths.push_back(a);
      ++res.summary.censored;
    }

  TrackStatsSummary &s = res.summary;
  s.frames = res.frames.size();
  std::vector<double> tracked, share, low, grad, noise, mean;
  for (size_t k = 0; k < res.frames.size(); ++k) {
    const auto &f = res.frames[k];
    if (k > 0) {
      tracked.push_back(f.tracked);
      share.push_back(f.new_share);
    }
    low.push_back(f.low_gradient_share);
    grad.push_back(f.gradient_median);
    noise.push_back(f.noise_sigma);
    mean.push_back(f.mean_intensity);
  }
  s.tracked_median = quantile(tracked, 0.5);
  s.new_share_mean = share.empty() ? 0.0 : std::accumulate(share.begin(), share.end(), 0.0) / share.size();
  s.new_share_median = quantile(share, 0.5);
  s.tracks = res.track_lengths.size();
  s.track_length_median = quantile(res.track_lengths, 0.5);
  s.track_length_p25 = quantile(res.track_lengths, 0.25);
  s.track_length_p75 = quantile(res.track_lengths, 0.75);
  s.track_length_mean =
      s.tracks ? std::accumulate(res.track_lengths.begin(), res.track_lengths.end(), 0.0) / s.tracks : 0.0;
  s.fb_median_px = quantile(res.fb_errors, 0.5);
  s.fb_p90_px = quantile(res.fb_errors, 0.9);
  const size_t rejected =
      std::count_if(res.fb_errors.begin(), res.fb_errors.end(), [&](double e) { return e >= opt.fb_max_px; });
  s.fb_reject_share = res.fb_errors.empty() ? 0.0 : static_cast<double>(rejected) / res.fb_errors.size();
  s.low_gradient_share = std::accumulate(low.begin(), low.end(), 0.0) / low.size();
  s.gradient_median = quantile(grad, 0.5);
  s.noise_sigma = quantile(noise, 0.5);
  s.mean_intensity = quantile(mean, 0.5);
  return res;
}

} // namespace

double noise_sigma_estimate(const cv::Mat &gray8) {
  if (gray8.rows < 3 || gray8.cols < 3)
    return 0.0;
  const cv::Mat kernel = (cv::Mat_<float>(3, 3) << 1, -2, 1, -2, 4, -2, 1, -2, 1);
  cv::Mat r;
  cv::filter2D(gray8, r, CV_32F, kernel, cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
  const cv::Rect inner(1, 1, gray8.cols - 2, gray8.rows - 2);
  const double sum_abs = cv::norm(r(inner), cv::NORM_L1);
  return std::sqrt(M_PI / 2.0) * sum_abs / (6.0 * inner.area());
}

GradientStats gradient_stats(const cv::Mat &gray8, double low_gradient) {
  if (gray8.empty() || gray8.type() != CV_8U)
    throw ovton::core::UsageError("gradient statistics need an 8-bit grey image");
  cv::Mat gx, gy, mag;
  cv::Sobel(gray8, gx, CV_32F, 1, 0, 3);
  cv::Sobel(gray8, gy, CV_32F, 0, 1, 3);
  cv::magnitude(gx, gy, mag);
  // A histogram in 0.5-unit bins gives median and 90th percentile without sorting 360k values per frame.
  constexpr int kBins = 4096;
  std::vector<int> hist(kBins, 0);
  size_t low = 0;
  for (int v = 0; v < mag.rows; ++v) {
    const float *m = mag.ptr<float>(v);
    for (int u = 0; u < mag.cols; ++u) {
      low += m[u] < low_gradient;
      ++hist[std::min(kBins - 1, static_cast<int>(m[u] * 2.0f))];
    }
  }
  const size_t n = static_cast<size_t>(mag.total());
  const auto at_quantile = [&](double q) {
    size_t acc = 0;
    for (int b = 0; b < kBins; ++b) {
      acc += hist[b];
      if (acc > q * n)
        return (b + 0.5) / 2.0;
    }
    return (kBins - 0.5) / 2.0;
  };
  GradientStats g;
  g.low_share = static_cast<double>(low) / n;
  g.median = at_quantile(0.5);
  g.p90 = at_quantile(0.9);
  g.noise_sigma = noise_sigma_estimate(gray8);
  g.mean_intensity = cv::mean(gray8)[0];
  return g;
}

TrackStatsResult track_statistics(const std::vector<std::pair<int64_t, std::string>> &images,
                                  const TrackStatsOptions &opt) {
  return run(
      images.size(), [&](size_t i) { return images[i].first; },
      [&](size_t i) {
        cv::Mat img = ovton::core::read_gray_image(images[i].second);
        if (img.empty())
          throw ovton::core::DataError(images[i].second, "cannot read image");
        return img;
      },
      opt);
}

TrackStatsResult track_statistics(const std::vector<std::pair<int64_t, cv::Mat>> &images,
                                  const TrackStatsOptions &opt) {
  return run(
      images.size(), [&](size_t i) { return images[i].first; },
      [&](size_t i) {
        if (images[i].second.type() != CV_8U)
          throw ovton::core::UsageError("trackstats: images must be 8-bit grey");
        return images[i].second;
      },
      opt);
}

std::string summary_yaml(const TrackStatsSummary &s, const TrackStatsOptions &o) {
  char buf[2048];
  std::snprintf(buf, sizeof(buf),
                "frames: %zu\n"
                "tracked_per_frame_median: %.1f\n"
                "new_feature_share_mean: %.4f\n"
                "new_feature_share_median: %.4f\n"
                "tracks: %zu  # features seen in >= 2 frames\n"
                "tracks_alive_at_end: %zu  # included with their length so far\n"
                "detections_lost_at_once: %zu\n"
                "track_length_median: %.1f\n"
                "track_length_p25: %.1f\n"
                "track_length_p75: %.1f\n"
                "track_length_mean: %.2f\n"
                "fb_error_median_px: %.3f\n"
                "fb_error_p90_px: %.3f\n"
                "fb_reject_share: %.4f  # LK-found points with a round trip >= %.2f px\n"
                "low_gradient_share: %.4f  # Sobel magnitude < %.0f, mean over frames\n"
                "gradient_median: %.2f\n"
                "noise_sigma: %.2f  # grey levels, Immerkaer estimate, median over frames\n"
                "mean_intensity: %.1f\n"
                "tracker: {points: %d, window: %d, pyramid_levels: %d, fb_max_px: %.2f, mask_radius_px: %.1f, "
                "gftt_quality: %.3f, gftt_block: %d}\n",
                s.frames, s.tracked_median, s.new_share_mean, s.new_share_median, s.tracks, s.censored, s.lost_at_once,
                s.track_length_median, s.track_length_p25, s.track_length_p75, s.track_length_mean, s.fb_median_px,
                s.fb_p90_px, s.fb_reject_share, o.fb_max_px, s.low_gradient_share, o.low_gradient, s.gradient_median,
                s.noise_sigma, s.mean_intensity, o.max_points, o.win_size, o.pyr_levels, o.fb_max_px, o.mask_radius_px,
                o.gftt_quality, o.gftt_block);
  return buf;
}

std::string frames_csv(const TrackStatsResult &r) {
  std::ostringstream os;
  os << "timestamp_ns,tracked,detected,new_share,fb_median_px,low_gradient_share,gradient_median,noise_sigma,"
        "mean_intensity\n";
  char buf[256];
  for (const auto &f : r.frames) {
    std::snprintf(buf, sizeof(buf), "%lld,%d,%d,%.4f,%.4f,%.4f,%.2f,%.3f,%.2f\n", static_cast<long long>(f.t_cam_ns),
                  f.tracked, f.detected, f.new_share, f.fb_median_px, f.low_gradient_share, f.gradient_median,
                  f.noise_sigma, f.mean_intensity);
    os << buf;
  }
  return os.str();
}

void save_trackstats_plot(const TrackStatsResult &r, const std::string &title, const std::string &png_file) {
  std::vector<double> t, tracked, share, low;
  const int64_t t0 = r.frames.empty() ? 0 : r.frames.front().t_cam_ns;
  std::vector<double> t_after_first;
  for (const auto &f : r.frames) {
    t.push_back((f.t_cam_ns - t0) * 1e-9);
    tracked.push_back(f.tracked);
    low.push_back(100.0 * f.low_gradient_share);
    if (f.t_cam_ns != t0) { // the first frame is all new and would flatten the rest of the curve
      t_after_first.push_back(t.back());
      share.push_back(100.0 * f.new_share);
    }
  }
  const auto panel = [&](const std::string &name, const std::string &xl, const std::string &yl) {
    PlotOptions po;
    po.title = title.empty() ? name : title + ": " + name;
    po.xlabel = xl;
    po.ylabel = yl;
    po.width = 700;
    po.height = 420;
    po.legend = false;
    return Plot(po);
  };
  Plot p1 = panel("tracked points per frame", "time [s]", "points");
  p1.add(Series("tracked", t, tracked));
  Plot p2 = panel("new features per frame", "time [s]", "new share [%]");
  p2.add(Series("new", t_after_first, share));
  // Histogram of track lengths in unit bins, drawn as points joined by a line.
  int max_len = 2;
  for (int l : r.track_lengths)
    max_len = std::max(max_len, l);
  std::vector<double> bins(max_len + 1, 0.0), xs(max_len + 1);
  for (int l : r.track_lengths)
    bins[l] += 1.0;
  std::iota(xs.begin(), xs.end(), 0.0);
  Plot p3 = panel("track lengths (" + std::to_string(r.track_lengths.size()) + " tracks)", "length [frames]", "tracks");
  p3.add(Series("lengths", xs, bins));
  Plot p4 = panel("plain pixels (low Sobel)", "time [s]", "share [%]");
  p4.add(Series("low gradient", t, low));
  cv::Mat top, bottom, all;
  cv::hconcat(p1.render(), p2.render(), top);
  cv::hconcat(p3.render(), p4.render(), bottom);
  cv::vconcat(top, bottom, all);
  std::vector<uchar> bytes;
  if (!ovton::core::encode_image(".png", all, bytes))
    throw ovton::core::DataError(png_file, "cannot encode the chart as PNG");
  std::ofstream f(png_file, std::ios::binary);
  f.write(reinterpret_cast<const char *>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!f)
    throw ovton::core::DataError(png_file, "cannot write PNG");
}

} // namespace ovton::eval
