// `ovton diagnose`: names the effect the filter's model lacks from its residual log (ov_eval/diagnose.h).
#include "ov_core/io/dataset.h"
#include "ov_core/types/errors.h"
#include "ov_eval/diagnose.h"
#include "tools/cli.h"
#include "tools/commands.h"

#include <boost/program_options.hpp>
#include <filesystem>
#include <iostream>

namespace po = boost::program_options;

int ovton::cli::cmd_diagnose(const ovton::cli::Args &args) {
  std::string log_file, dataset_dir, out_dir, calib_file;
  bool nominal = false;
  int camera = -1;
  ovton::eval::DiagnoseOptions opt;
  po::options_description desc(
      "usage: ovton diagnose --log FILE [--dataset DIR] [--out DIR]\n\n"
      "Tests candidate effects on the log that `ovton run --residual-log FILE` wrote. With --dataset, the\n"
      "effects a filter's state absorbs (time offset constant / drifting, rolling-shutter readout, focal\n"
      "error, gyro scale) are tested on the images' angular rate and its change down the rows against the\n"
      "raw gyro; principal-point and radial-distortion error on the residuals. Without --dataset all of\n"
      "them on the residuals (lower bounds). Ranks them by the share of their data they explain and says\n"
      "which are significant; what the log cannot resolve (too short, too few independent clusters, a platform\n"
      "that did not move) is reported as not testable on it. Writes diagnose.md, diagnose.json and PNG plots\n"
      "(docs/diagnose.md). A rig's further cameras have logs of their own (res_cam1.csv beside res.csv), each\n"
      "diagnosed with that camera's calibration.\n\noptions");
  // clang-format off
  desc.add_options()
    ("help,h", "print this help")
    ("log", po::value(&log_file), "residual log CSV (ovton run --residual-log)")
    ("dataset", po::value(&dataset_dir),
     "dataset folder the log was made from: camera (intrinsics, distortion, camera-body rotation, height) and "
     "raw IMU (default: height and intrinsics from the log; time candidates on the residual)")
    ("camera", po::value(&camera),
     "the rig's camera whose rows the log holds (default: K for a log named *_camK.csv, else 0, the primary); "
     "its calibration is taken from --dataset")
    ("calibration-log", po::value(&calib_file),
     "the filter's calibration per update (default: <log>_calib.csv beside the log when it exists, which `ovton run "
     "--residual-log` writes); the rates compare the images with the IMU through it")
    ("nominal-calibration", po::bool_switch(&nominal),
     "ignore the calibration log: compare through the dataset's calibration only")
    ("out", po::value(&out_dir), "output folder (default: <log without extension>_diagnose beside the log)")
    ("min-sigma", po::value(&opt.min_sigma)->default_value(opt.min_sigma, "5"),
     "significance a candidate needs [Gaussian sigma of its Wald test, against F with the data's independent clusters]")
    ("min-explained", po::value(&opt.min_explained)->default_value(opt.min_explained, "0.02"),
     "share of the residual loss a candidate must remove (0..1)")
    ("logged-velocity", po::bool_switch(&opt.use_logged_velocity),
     "use the log's velocity column (shares each row's pixel noise: biased) instead of the track's central difference")
    ("time-bins", po::value(&opt.time_bins)->default_value(opt.time_bins), "bins of the per-time offset estimate")
    ("gravity", po::value(&opt.gravity_mag)->default_value(opt.gravity_mag, "9.81"),
     "|g| [m/s^2] the accelerometer scale is tested against (the run's estimator gravity_mag)");
  // clang-format on
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0; // --help
  if (log_file.empty())
    throw ovton::core::UsageError("--log is required (see ovton diagnose --help)");
  if (!(opt.min_sigma > 0) || !(opt.min_explained >= 0 && opt.min_explained < 1) || opt.time_bins < 1)
    throw ovton::core::UsageError("--min-sigma must be > 0, --min-explained in [0, 1), --time-bins >= 1");
  if (!(opt.gravity_mag > 9.7 && opt.gravity_mag < 9.9))
    throw ovton::core::UsageError("--gravity must be between 9.7 and 9.9 m/s^2 (Earth's surface)");
  if (camera < 0)
    camera = ovton::core::camera_of_residual_log(log_file);
  if (camera > 0) {
    std::cout << "camera " << camera << "'s rows" << (vm.count("camera") ? "" : " (from the log's file name)") << "\n";
    // The calibration log is the filter's primary camera's (its extrinsics and intrinsics): not this camera's.
    if (!calib_file.empty())
      throw ovton::core::UsageError("--calibration-log holds the primary camera's calibration: not for camera " +
                                    std::to_string(camera) + "'s log (leave it out)");
    nominal = true;
  }
  if (!dataset_dir.empty()) {
    ovton::core::LoadOptions lo;
    lo.check_images_exist = false;
    const ovton::core::Dataset data = ovton::core::load_dataset(dataset_dir, lo);
    if (static_cast<size_t>(camera) >= data.num_cameras())
      throw ovton::core::UsageError("camera " + std::to_string(camera) + ": the dataset " + dataset_dir + " has " +
                                    std::to_string(data.num_cameras()) + " camera(s)");
    const ovton::core::CameraCalib &cam = camera == 0 ? data.cam : data.more_cameras[camera - 1].cam;
    opt.image_height = cam.height;
    opt.fu = cam.intrinsics(0), opt.fv = cam.intrinsics(1);
    opt.cu = cam.intrinsics(2), opt.cv = cam.intrinsics(3);
    opt.camera = cam;
    opt.have_camera = true;
    opt.imu = data.imu;
  }
  if (out_dir.empty()) {
    std::filesystem::path p(log_file);
    out_dir = (p.parent_path() / (p.stem().string() + "_diagnose")).string();
  }
  const ovton::eval::ResidualLog log = ovton::eval::load_residual_log(log_file);
  if (calib_file.empty() && !nominal && std::filesystem::exists(ovton::core::calibration_log_path(log_file)))
    calib_file = ovton::core::calibration_log_path(log_file);
  if (!calib_file.empty() && !nominal) {
    opt.calibration = ovton::core::load_calibration_log(calib_file);
    std::cout << "filter's calibration: " << calib_file << " (" << opt.calibration.size() << " updates)\n";
  }
  const ovton::eval::DiagnoseReport rep = ovton::eval::diagnose(log, opt);
  std::cout << "log " << log_file << ": " << rep.rows_used << " observations in " << rep.tracks_used << " tracks over "
            << rep.duration_s << " s, residual RMS " << rep.residual_rms_px << " px\n\n"
            << ovton::eval::format_ranking(rep) << "\n";
  for (const auto &f : ovton::eval::write_diagnose_report(rep, out_dir))
    std::cout << "wrote " << f << "\n";
  return 0;
}
