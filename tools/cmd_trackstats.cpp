// `ovton trackstats`: how hard a folder's images are for a KLT front end (docs/simulate.md, "Realism").
#include "ov_core/io/dataset.h"
#include "ov_core/types/errors.h"
#include "ov_eval/trackstats.h"
#include "tools/cli.h"
#include "tools/commands.h"

#include <boost/program_options.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace ovton::cli {

namespace {

void write_file(const fs::path &p, const std::string &text) {
  std::ofstream f(p);
  f << text;
  f.close();
  if (!f)
    throw ovton::core::DataError(p.string(), "cannot write");
}

int64_t seconds_to_ns_option(double s, const char *name) {
  if (!std::isfinite(s))
    throw ovton::core::UsageError(std::string("--") + name + " must be finite");
  return ovton::core::s_to_ns(s);
}

} // namespace

int cmd_trackstats(const Args &args) {
  po::options_description desc(
      "ovton trackstats: track statistics of a folder's images (real or rendered) with a plain OpenCV KLT check\n"
      "(Shi-Tomasi + pyramidal LK, forward-backward check): tracked points, new-feature share, track lengths,\n"
      "forward-backward error, image gradients and noise");
  std::string dataset, out;
  ovton::eval::TrackStatsOptions o;
  double from_s = NAN, to_s = NAN;
  desc.add_options()("help,h", "this help")                                                                   //
      ("dataset,d", po::value(&dataset)->required(), "EuRoC folder (the one holding mav0/)")                  //
      ("out,o", po::value(&out), "write summary.yaml, frames.csv and trackstats.png into this folder")        //
      ("from-s", po::value(&from_s), "first image stamp to use [s, camera clock, absolute]")                  //
      ("to-s", po::value(&to_s), "last image stamp to use [s, camera clock, absolute]")                       //
      ("points", po::value(&o.max_points)->default_value(200), "points kept alive")                           //
      ("window", po::value(&o.win_size)->default_value(21), "LK window side [px]")                            //
      ("levels", po::value(&o.pyr_levels)->default_value(3), "pyramid images (OpenCV maxLevel + 1)")          //
      ("fb-max-px", po::value(&o.fb_max_px)->default_value(0.5), "forward-backward threshold [px]")           //
      ("mask-px", po::value(&o.mask_radius_px)->default_value(15.0), "no new point this close to a live one") //
      ("low-gradient", po::value(&o.low_gradient)->default_value(20.0), "Sobel magnitude counted as plain");
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0;
  if (vm.count("from-s"))
    o.t_begin_ns = seconds_to_ns_option(from_s, "from-s");
  if (vm.count("to-s"))
    o.t_end_ns = seconds_to_ns_option(to_s, "to-s");
  const ovton::core::Dataset data = ovton::core::load_dataset(dataset);
  std::vector<std::pair<int64_t, std::string>> images;
  for (const auto &im : data.images) {
    if (im.features)
      throw ovton::core::UsageError(dataset + " is a feature-level folder (cam0/features.csv): no images to track");
    images.emplace_back(im.t_cam_ns, im.path);
  }
  const ovton::eval::TrackStatsResult r = ovton::eval::track_statistics(images, o);
  const std::string yaml = ovton::eval::summary_yaml(r.summary, o);
  std::cout << "dataset: " << dataset << "\n" << yaml;
  if (!out.empty()) {
    fs::create_directories(out);
    write_file(fs::path(out) / "summary.yaml", "dataset: " + dataset + "\n" + yaml);
    write_file(fs::path(out) / "frames.csv", ovton::eval::frames_csv(r));
    ovton::eval::save_trackstats_plot(r, fs::path(dataset).filename().string(),
                                      (fs::path(out) / "trackstats.png").string());
    std::cout << "wrote " << out << "/{summary.yaml,frames.csv,trackstats.png}\n";
  }
  return 0;
}

} // namespace ovton::cli
