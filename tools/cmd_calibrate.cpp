// `ovton calibrate --dataset DIR [--out DIR2]`: a recording that comes without calibration (no sensor.yaml) is given
// one from its own images and gyro (ov_msckf_ton/calib/camera_imu_calib.h), written as EuRoC sensor.yaml files,
// Kalibr files and an estimator config, so that `ovton run -d DIR2 -c DIR2/ovton_config.yaml` then runs.
#include "ov_core/io/dataset.h"
#include "ov_core/io/kalibr_writer.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/calib/camera_imu_calib.h"
#include "ov_sim/euroc_calib.h"
#include "tools/cli.h"
#include "tools/commands.h"

#include <algorithm>
#include <boost/program_options.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace ovton::cli {
namespace {

/// Steps of time-ordered stamps: min, median, max [ms] and how many exceed twice the median.
std::string step_report(const std::vector<int64_t> &t) {
  std::vector<double> dt;
  for (size_t i = 1; i < t.size(); ++i)
    dt.push_back(static_cast<double>(t[i] - t[i - 1]) * 1e-6);
  if (dt.empty())
    return "no steps";
  std::vector<double> s = dt;
  std::sort(s.begin(), s.end());
  const double med = s[s.size() / 2];
  const long over = std::count_if(dt.begin(), dt.end(), [&](double x) { return x > 2 * med; });
  char out[200];
  std::snprintf(out, sizeof out, "steps min %.2f / median %.2f / max %.2f ms, %ld above twice the median", s.front(),
                med, s.back(), over);
  return out;
}

void print_streams(const ovton::core::Dataset &d) {
  std::vector<int64_t> tc, ti;
  for (const auto &e : d.images)
    tc.push_back(e.t_cam_ns);
  for (const auto &m : d.imu)
    ti.push_back(m.t_imu_ns);
  std::cout << "dataset   " << d.root << " (" << d.notes << ")\n"
            << "images    " << d.images.size() << ", " << d.cam.rate_hz << " Hz; " << step_report(tc) << "\n"
            << "imu       " << d.imu.size() << ", " << d.imu_calib.rate_hz << " Hz; " << step_report(ti) << "\n";
  if (const std::string g = d.imu_gaps.summary(); !g.empty())
    std::cout << "          " << g << "\n";
}

std::string config_text(const ovton::msckf::CalibResult &c, const std::string &source) {
  // The filter refines what was estimated: its prior σ are the calibration's, widened to 3σ (a first fit on a
  // handheld recording; the halves of one recording may disagree by more than one σ) and floored where a σ of
  // nearly zero would freeze a quantity the filter should still be free to move.
  const double s_rot = std::max(0.005, 3 * c.sigma_rot_rad.maxCoeff());
  std::ostringstream os;
  os.precision(6);
  os << "# Written by `ovton calibrate` for " << source << ": the calibration's estimates as the filter's start,\n"
     << "# its sigma (x3) as the online calibration's priors. Everything else: the built-in defaults.\n"
     << "time_offset:\n  mode: sr\n  init_s: " << c.td_s << "\n  sigma_init_s: " << std::max(0.002, 3 * c.sigma_td_s)
     << "\n  search: false              # the calibration's fit is the coarse search\n"
     << "calibration:\n  extrinsics: true\n  sigma_ext_rot: " << s_rot
     << "\n  sigma_ext_pos: 0.02          # lever arm unknown (zero written): a phone's is a few cm\n"
     << "  intrinsics: true\n  sigma_focal_px: " << std::max(2.0, 3 * c.sigma_focal_px)
     << "\n  sigma_center_px: 5.0\n  sigma_distortion: 0.02\n";
  if (c.readout_estimated)
    os << "  readout: true\n  readout_s: " << std::max(0.0, c.readout_s)
       << "\n  sigma_readout_s: " << std::max(0.002, 3 * c.sigma_readout_s) << "\n";
  os << "init:\n  mode: auto\n";
  return os.str();
}

void write_text(const fs::path &file, const std::string &text) {
  fs::create_directories(file.parent_path());
  std::ofstream f(file);
  f << text;
  if (!f)
    throw ovton::core::DataError(file.string(), "cannot write");
}

} // namespace

int cmd_calibrate(const Args &args) {
  po::options_description desc("ovton calibrate: estimate R_IC, focal length, t_d and readout of a recording "
                               "without calibration (images' rotation against the gyro)");
  std::string dir, out, model = "epipolar";
  double hfov = 67.5, range_ms = 200, prior_ms = 0, from_s = 0, to_s = 0;
  bool force = false, no_readout = false;
  std::string start_yaml;
  double start_td_ms = 0, start_tr_ms = 0;
  ovton::msckf::CalibOptions opt;
  desc.add_options()("help,h", "this help")                                                                      //
      ("dataset,d", po::value(&dir)->required(), "EuRoC-layout folder (mav0/cam0/data.csv, mav0/imu0/data.csv)") //
      ("out,o", po::value(&out),
       "write here (OUT/mav0/{cam0,imu0}/sensor.yaml with links to the data, OUT/ovton_config.yaml, OUT/kalibr/); "
       "default: beside the data")                                                           //
      ("force", po::bool_switch(&force), "overwrite existing calibration files")             //
      ("hfov-deg", po::value(&hfov), "prior horizontal field of view [deg] (default 67.5)")  //
      ("td-range-ms", po::value(&range_ms), "coarse grid: prior ± range [ms] (default 200)") //
      ("td-prior-ms", po::value(&prior_ms), "centre of the grid [ms] (default 0)")           //
      ("model", po::value(&model),
       "epipolar (default: per pair, translation direction solved) | rotation (Huber on pure-rotation reprojection)") //
      ("no-readout", po::bool_switch(&no_readout), "global shutter: do not estimate a readout time")                  //
      ("from-s", po::value(&from_s), "use images from this many seconds after the first")                             //
      ("to-s", po::value(&to_s), "... up to this many (default: the end)")                                            //
      ("start-cam-yaml", po::value(&start_yaml),
       "refine this EuRoC cam0/sensor.yaml's R_IC and focal (with --start-td-ms) instead of searching")      //
      ("start-td-ms", po::value(&start_td_ms), "with --start-cam-yaml: the offset to start from [ms]")       //
      ("start-readout-ms", po::value(&start_tr_ms), "with --start-cam-yaml: the readout to start from [ms]") //
      ("iterations", po::value(&opt.max_iterations), "Levenberg-Marquardt iterations at most (0: evaluate the start)");
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0;
  if (!(hfov > 10 && hfov < 170))
    throw ovton::core::UsageError("--hfov-deg must lie in (10, 170)");
  if (!(range_ms > 0 && range_ms <= 2000))
    throw ovton::core::UsageError("--td-range-ms must lie in (0, 2000]");
  opt.hfov_prior_deg = hfov;
  if (!start_yaml.empty()) {
    const ovton::core::CameraCalib s = ovton::core::load_euroc_camera_yaml(start_yaml);
    opt.has_start = true;
    opt.start_R_IC = s.T_BC.block<3, 3>(0, 0);
    opt.start_focal_px = s.intrinsics(0);
    opt.start_td_s = start_td_ms * 1e-3;
    opt.start_readout_s = start_tr_ms * 1e-3;
  }
  opt.td_range_s = range_ms * 1e-3;
  opt.td_prior_s = prior_ms * 1e-3;
  opt.model = ovton::msckf::parse_calib_model(model);
  opt.estimate_readout = !no_readout;

  const ovton::core::Dataset d = ovton::core::load_euroc_streams(dir);
  print_streams(d);
  const ovton::msckf::ImuNoiseEstimate noise = ovton::msckf::estimate_imu_noise(d.imu);
  std::cout << noise.summary() << "\n";
  const ovton::msckf::CalibResult c = ovton::msckf::calibrate_recording(d, from_s, to_s, opt);
  std::cout << "model " << model << "\n" << c.summary() << "\n";

  // Where to write: OUT (a new folder whose mav0 links to the data) or the data's own mav0.
  const fs::path src_mav0 = fs::is_directory(fs::path(dir) / "mav0") ? fs::path(dir) / "mav0" : fs::path(dir);
  const fs::path root = out.empty() ? src_mav0.parent_path() : fs::path(out);
  const fs::path mav0 = out.empty() ? src_mav0 : root / "mav0";
  const std::vector<fs::path> files = {mav0 / "cam0/sensor.yaml",  mav0 / "imu0/sensor.yaml",
                                       root / "ovton_config.yaml", root / "kalibr/camchain-imucam.yaml",
                                       root / "kalibr/imu.yaml",   root / "calibration.txt"};
  for (const auto &f : files)
    if (fs::exists(f) && !force)
      throw ovton::core::UsageError(f.string() + " exists: use --force to overwrite it");
  ovton::core::CameraCalib cam;
  cam.width = c.width;
  cam.height = c.height;
  cam.rate_hz = d.cam.rate_hz;
  cam.intrinsics << c.focal_px, c.focal_px, c.cu, c.cv;
  cam.T_BC.block<3, 3>(0, 0) = c.R_IC;
  const std::string note = "estimated by ovton calibrate from " + fs::absolute(dir).string();
  write_text(files[0], ovton::sim::euroc_camera_yaml(cam, note));
  write_text(files[1], ovton::sim::euroc_imu_yaml(noise.calib, note + ", noise figures in calibration.txt"));
  write_text(files[2], config_text(c, fs::absolute(dir).string()));
  fs::create_directories(root / "kalibr");
  ovton::core::write_kalibr_camchain(files[3].string(), cam, c.td_s, "/cam0/image_raw");
  ovton::core::write_kalibr_imu(files[4].string(), noise.calib, "/imu0");
  write_text(files[5], "# ovton calibrate --dataset " + fs::absolute(dir).string() + " --model " + model + "\n" +
                           c.summary() + "\n" + noise.summary() + "\n");
  if (!out.empty())
    for (const char *rel : {"cam0/data.csv", "cam0/data", "imu0/data.csv"}) {
      const fs::path link = mav0 / rel;
      if (fs::is_symlink(link) || fs::exists(link)) {
        if (!fs::is_symlink(link))
          continue; // the data themselves (OUT is the dataset): keep them
        fs::remove(link);
      }
      fs::create_symlink(fs::absolute(src_mav0 / rel), link);
    }
  std::cout << "wrote " << files[0].string() << ", " << files[1].string() << ", " << files[2].string() << ", "
            << (root / "kalibr").string() << "/, " << files[5].string() << "\nnext: ovton run -d " << root.string()
            << " -c " << files[2].string() << " -o traj.csv\n";
  return 0;
}

} // namespace ovton::cli
