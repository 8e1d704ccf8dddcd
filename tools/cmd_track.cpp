// `ovton track`: the front end alone. Tracks every image of a folder with the KLT tracker `ovton run` uses (same
// options, same tracks: the tracker does not depend on the filter) and writes them as cam0/features.csv rows, which
// `ovton run` replays instead of the images when the file sits in a folder's cam0/. With --score, measures tracks
// (these or any features.csv, e.g. another system's) against the ground truth (ov_eval/track_truth.h).
#include "ov_core/cam/camera_model.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_store.h"
#include "ov_core/track/track_klt.h"
#include "ov_core/types/errors.h"
#include "ov_eval/track_truth.h"
#include "ov_msckf_ton/core/vio_options.h"
#include "tools/cli.h"
#include "tools/commands.h"
#include "tools/run_pipeline.h"

#include <boost/program_options.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <stdexcept>

namespace po = boost::program_options;

int ovton::cli::cmd_track(const ovton::cli::Args &args) {
  std::string dataset_dir, config, out_file, tracks_file, md_file, rewrite;
  uint64_t seed = 1;
  bool score = false;
  long max_images = 0;
  ovton::eval::TrackTruthOptions so;
  po::options_description desc(
      "usage: ovton track --dataset DIR [--config F] [--out features.csv] [--score] [--tracks F]\n\n"
      "Runs the KLT front end of `ovton run` (the config's tracker section) over a folder's images and writes\n"
      "every tracked point as timestamp_ns,feature_id,u,v (cam0/features.csv format: put it in a copy of the\n"
      "folder's cam0/ and `ovton run` uses these tracks instead of the images). --score fits each track's point\n"
      "with the ground-truth camera poses held fixed and reports the tracker's pixel error (size, bias, outliers,\n"
      "correlation along a track) and track lengths; --tracks scores an existing features.csv instead of tracking.\n\n"
      "options");
  // clang-format off
  desc.add_options()
    ("help,h", "print this help")
    ("dataset,d", po::value(&dataset_dir), "dataset folder (EuRoC layout)")
    ("config,c", po::value(&config), "estimator config YAML (its tracker section; default: built-in defaults)")
    ("out,o", po::value(&out_file), "write the tracks here (features.csv format)")
    ("tracks", po::value(&tracks_file), "score this features.csv instead of tracking")
    ("score", po::bool_switch(&score), "score the tracks against the ground truth")
    ("md", po::value(&md_file), "also write the score table to this Markdown file")
    ("max-images", po::value(&max_images), "stop after this many images")
    ("rewrite", po::value(&rewrite),
     "experiment: write (--out) each fitted track as its point's exact projections plus: truth (nothing), white:S "
     "(Gaussian, S px), ar1:S:RHO (Gaussian correlated along the track), shuffle (the tracker's own errors permuted "
     "across tracks)")
    ("seed", po::value(&seed)->default_value(seed), "random seed of --rewrite")
    ("max-segment", po::value(&so.max_segment)->default_value(so.max_segment),
     "score tracks in pieces of at most this many observations (the filter's window)");
  // clang-format on
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0; // --help
  if (dataset_dir.empty())
    throw ovton::core::UsageError("--dataset is required (see ovton track --help)");
  if (tracks_file.empty() && out_file.empty() && !score && rewrite.empty())
    throw ovton::core::UsageError("nothing to do: give --out, --score or --tracks");
  ovton::core::LoadOptions lo;
  lo.check_images_exist = tracks_file.empty();
  const ovton::core::Dataset data = ovton::core::load_dataset(dataset_dir, lo);

  std::vector<ovton::eval::TrackPoint> points;
  if (!tracks_file.empty()) {
    points = ovton::eval::read_track_points(tracks_file);
    score = score || (rewrite.empty() && out_file.empty());
  } else {
    const ovton::msckf::VioOptions opt =
        config.empty() ? ovton::msckf::VioOptions{} : ovton::msckf::load_vio_options(config);
    const ovton::core::CameraModel camera(data.cam);
    ovton::core::TrackKLT tracker(camera, opt.track);
    tracker.set_rotation_prior(ovton::rotation_prior_for(data, opt));
    long n = 0, feats = 0;
    for (const auto &e : data.images) {
      if (max_images > 0 && n >= max_images)
        break;
      const cv::Mat gray = ovton::core::load_image(e);
      if (gray.empty())
        throw ovton::core::DataError(e.path, "unreadable image");
      const auto &tracked = tracker.track(e.t_cam_ns, gray);
      ++n;
      feats += static_cast<long>(tracked.size());
      for (const auto &f : tracked) // exact: written with %.17g below
        points.push_back({e.t_cam_ns, f.id, f.uv});
    }
    const auto &t = tracker.totals();
    std::printf("tracked %ld images, %.1f features per image; tracker %.2f ms/frame (pyramid %.2f, KLT %.2f, "
                "RANSAC %.2f, detection %.2f)\n",
                n, n ? static_cast<double>(feats) / static_cast<double>(n) : 0.0, t.mean(t.t_total_ms),
                t.mean(t.t_pyramid_ms), t.mean(t.t_tracking_ms), t.mean(t.t_ransac_ms), t.mean(t.t_detection_ms));
  }
  if (!rewrite.empty()) {
    if (out_file.empty())
      throw ovton::core::UsageError("--rewrite needs --out");
    ovton::eval::TrackRewrite how = ovton::eval::TrackRewrite::Truth;
    double sigma = 0, rho = 0;
    const auto num = [&](size_t from) {
      const size_t c = rewrite.find(':', from);
      return std::stod(rewrite.substr(from, c == std::string::npos ? std::string::npos : c - from));
    };
    try {
      if (rewrite == "truth")
        how = ovton::eval::TrackRewrite::Truth;
      else if (rewrite == "shuffle")
        how = ovton::eval::TrackRewrite::Shuffle;
      else if (rewrite.rfind("white:", 0) == 0) {
        how = ovton::eval::TrackRewrite::White;
        sigma = num(6);
      } else if (rewrite.rfind("ar1:", 0) == 0 && rewrite.find(':', 4) != std::string::npos) {
        how = ovton::eval::TrackRewrite::Ar1;
        sigma = num(4);
        rho = num(rewrite.find(':', 4) + 1);
      } else
        throw std::invalid_argument(rewrite);
    } catch (const std::logic_error &) {
      throw ovton::core::UsageError("--rewrite: expected truth, white:S, ar1:S:RHO or shuffle, got '" + rewrite + "'");
    }
    points = ovton::eval::rewrite_tracks(points, data, how, sigma, rho, seed, so);
  }
  if (!out_file.empty()) {
    std::ofstream out(out_file);
    if (!out)
      throw ovton::core::DataError(out_file, "cannot open for writing");
    out << "#timestamp_ns,feature_id,u,v\n";
    char buf[128];
    for (const auto &p : points) {
      // %.17g round-trips a double: `ovton run` on the file sees exactly the numbers the tracker gave.
      std::snprintf(buf, sizeof(buf), "%lld,%llu,%.17g,%.17g\n", static_cast<long long>(p.t_cam_ns),
                    static_cast<unsigned long long>(p.id), p.uv.x(), p.uv.y());
      out << buf;
    }
    if (!out)
      throw ovton::core::DataError(out_file, "write failed");
  }
  if (score) {
    const ovton::eval::TrackTruthResult r = ovton::eval::score_tracks(points, data, so);
    const std::string table = ovton::eval::track_truth_table(r);
    std::cout << table;
    if (!md_file.empty()) {
      std::ofstream md(md_file);
      md << table;
      if (!md)
        throw ovton::core::DataError(md_file, "cannot write");
    }
  }
  return 0;
}
