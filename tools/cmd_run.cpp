// `ovton run`: replay a dataset folder through the estimator and write the trajectory.
#include "ov_core/io/csv.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/types/errors.h"
#include "ov_eval/init_check.h"
#include "ov_eval/metrics.h"
#include "ov_msckf_ton/td/td_model_check.h"
#include "ov_msckf_ton/td/td_models.h"
#include "tools/cli.h"
#include "tools/commands.h"
#include "tools/progress.h"
#include "tools/run_pipeline.h"

#include <algorithm>
#include <boost/program_options.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <opencv2/core/utility.hpp>
#include <thread>

namespace po = boost::program_options;

namespace ovton::cli {

int cmd_run(const Args &args) {
  po::options_description desc("ovton run: replay a dataset folder through the MSCKF and write its trajectory");
  std::string config, dataset, mode, format = "csv", init, nees_log, td_search, health, mcap_images = "jpeg", cameras;
  double td_init_ms = std::numeric_limits<double>::quiet_NaN();
  bool quiet = false, no_prefetch = false;
  int opencv_threads = -1;
  RunRequest req;
  desc.add_options()("help,h", "this help")                                                  //
      ("config,c", po::value(&config), "estimator config YAML (default: built-in defaults)") //
      ("dataset,d", po::value(&dataset)->required(),
       "dataset folder (EuRoC or SCube), ROS 1 bag, MCAP file or rosbag2 folder") //
      ("td-mode,m", po::value(&mode),
       "off|sr|sir|fvon|tpn|ton|oracle|drift, optionally +PROCESS (constant|random_walk|drift|tpn), e.g. "
       "sr+random_walk (overrides the config)")                                    //
      ("output,o", po::value(&req.output)->required(), "trajectory file to write") //
      ("format", po::value(&format), "csv (default) or tum")                       //
      ("cameras", po::value(&cameras),
       "the rig's cameras to use, e.g. 0 or 0,1 (the first is the primary; default: every camera the recording has, "
       "up to rig.max_cameras)") //
      ("residual-log", po::value(&req.residual_log),
       "write every feature residual of every update here (a rig's further cameras: FILE_camK.csv beside it)") //
      ("velocity-log", po::value(&req.velocity_log),
       "write each observation's image velocity by every rule and network here (for `ovton velocities`)") //
      ("init", po::value(&init),
       "static|groundtruth|auto|dynamic (overrides the config; auto: static when still, dynamic when moving)") //
      ("td-init-ms", po::value(&td_init_ms), "initial / fixed t_d [ms] (overrides the config)")                //
      ("td-search", po::value(&td_search),
       "on|off: coarse t_d search around the initial t_d before the filter starts (overrides time_offset.search; "
       "default on)") //
      ("health-checks", po::value(&health),
       "on|off: stop a run whose estimate has diverged, exit 4 (overrides health.enabled; default on)") //
      ("nees-log", po::value(&nees_log), "with --init groundtruth: write per-frame NEES (t_ns,ori,pos,td) here")(
          "max-images", po::value(&req.max_images), "stop after this many images") //
      ("mcap-out", po::value(&req.mcap_out),
       "also write the run as an MCAP file Foxglove opens (ROS 2 schemas): each image with its features (used, gated, "
       "tracked), estimated and true pose, /tf, paths, t_d with its sigma band and the truth; written as the run goes, "
       "closed whole on Ctrl-C (docs/bags.md)") //
      ("mcap-images", po::value(&mcap_images),
       "jpeg (CompressedImage, default) or raw (mono8 Image) images in --mcap-out") //
      ("no-prefetch", po::bool_switch(&no_prefetch),
       "one thread: decode, track and filter on the main thread, OpenCV's thread pool off too unless "
       "--opencv-threads is given (default: tracking and filter on threads of their own while the next image is "
       "decoded; same results)") //
      ("opencv-threads", po::value(&opencv_threads),
       "threads of OpenCV's own pool inside the tracker (0: none, its work on the calling thread; default: "
       "OpenCV's choice, 0 with --no-prefetch)") //
      ("quiet,q", po::bool_switch(&quiet), "no progress bar, no option listing");
  ovton::core::BagOptions bag_opt;
  add_bag_options(desc, bag_opt);
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0; // --help
  req.threaded = !no_prefetch && std::thread::hardware_concurrency() >= 2;
  // One thread means one: OpenCV's own pool (TBB in Debian's build, which OPENCV_FOR_THREADS_NUM does not stop) would
  // otherwise run part of the tracker on a second core (docs/benchmarks.md, "One thread is one thread").
  if (opencv_threads >= 0)
    cv::setNumThreads(opencv_threads);
  else if (no_prefetch)
    cv::setNumThreads(0);
  if (format != "csv" && format != "tum")
    throw ovton::core::UsageError("--format must be csv or tum");
  req.tum = format == "tum";
  if (mcap_images != "jpeg" && mcap_images != "raw")
    throw ovton::core::UsageError("--mcap-images must be jpeg or raw");
  req.mcap.image_format = mcap_images;
  req.progress = !quiet;

  req.opt = config.empty() ? ovton::msckf::VioOptions{} : ovton::msckf::load_vio_options(config);
  if (!mode.empty())
    ovton::msckf::apply_mode_spec(ovton::msckf::parse_mode_spec(mode), req.opt);
  if (!init.empty())
    req.opt.init.mode = ovton::msckf::parse_init_mode(init);
  if (vm.count("td-init-ms")) {
    if (!(std::abs(td_init_ms) <= 10000)) // NaN too: it would mean "not given"
      throw ovton::core::UsageError("--td-init-ms must be a number within +-10000 ms");
    req.opt.td.init_s = td_init_ms * 1e-3;
  }
  if (!td_search.empty())
    req.opt.td.search.enabled = parse_on_off(td_search, "--td-search");
  if (!health.empty())
    req.opt.health.enabled = parse_on_off(health, "--health-checks");
  // Every output is checked before the run: a typo should not cost a whole run.
  std::vector<std::string> outputs = {req.output};
  for (const auto *o : {&req.residual_log, &req.velocity_log, &nees_log, &req.mcap_out})
    if (!o->empty())
      outputs.push_back(*o);
  for (size_t i = 0; i < outputs.size(); ++i) {
    ovton::core::require_writable(outputs[i]);
    for (size_t j = 0; j < i; ++j)
      if (std::filesystem::weakly_canonical(outputs[i]) == std::filesystem::weakly_canonical(outputs[j]))
        throw ovton::core::UsageError("two outputs are the same file: " + outputs[i]);
  }

  ovton::core::Dataset data = ovton::core::load_recording(dataset, bag_opt);
  if (const std::string gaps = data.imu_gaps.summary(); !gaps.empty())
    std::cout << "note: " << gaps << " with the process noise of their length\n";
  for (const std::string &w : data.warnings)
    std::cerr << "warning: " << w << "\n";
  if (!cameras.empty())
    ovton::core::select_cameras(data, ovton::core::parse_camera_list(cameras));
  ovton::apply_dataset_defaults(data, vm.count("td-init-ms") > 0, req.opt);
  if (!quiet)
    ovton::msckf::print_vio_options(req.opt, std::cerr);

  install_interrupt_handler();
  RunResult r;
  try {
    r = run_dataset(data, req);
  } catch (const ovton::core::EstimatorFailure &e) {
    throw ovton::core::EstimatorFailure(e.t_ns(), std::string(e.what()) + "; the rows before it are in " + req.output);
  } catch (const ovton::core::DataError &e) {
    if (data.truncated_file.empty() || e.file() != data.truncated_file)
      throw;
    throw ovton::core::DataError(e.file(), data.truncated_reason + "; their rows are in " + req.output);
  }

  const auto &c = r.report.counters;
  const auto &tm = r.report.times;
  std::cout << std::fixed << std::setprecision(3);
  std::cout << "mode " << ovton::msckf::to_string(req.opt.td.mode) << ": " << r.play.images_fed << " images ("
            << c.images_before_init << " before initialisation, " << r.report.images_skipped << " beyond the IMU log), "
            << c.updates << " updates, " << c.features_used << " features used, " << c.features_gated << " gated, "
            << c.zupts << " zero-velocity updates, " << c.td_rows << " observations constraining t_d\n";
  if (c.frozen_frames > 0)
    std::cout << "note: " << c.frozen_frames << " images showed no motion while the filter's velocity said the body "
              << "moved (a frozen or re-sent camera frame): they were dropped\n";
  if (c.slam_initialised > 0)
    std::cout << "SLAM: " << c.slam_initialised << " landmarks initialised, " << c.slam_updates
              << " landmark observations used, " << c.slam_gated << " gated\n";
  std::cout << "t_d rows by velocity source: tracked " << c.td_rows_by_source[ovton::msckf::kVelocityTracked]
            << ", ITS-FVON " << c.td_rows_by_source[ovton::msckf::kVelocityItsFvon] << ", F2F-FVON "
            << c.td_rows_by_source[ovton::msckf::kVelocityF2fFvon] << " (" << c.td_features << " features); networks "
            << (tm.frames ? tm.networks / tm.frames : 0.0) << " ms/frame\n";
  std::cout << "initialisation: " << r.report.init_message << "\n";
  if (r.report.td_search)
    std::cout << "coarse t_d search: " << r.report.td_search->summary() << "\n";
  const auto &acc = r.report.acceptance;
  if (acc.examined() > 0)
    std::cout << "update acceptance " << 100.0 * acc.acceptance() << " % of " << acc.examined() << " features ("
              << acc.gated << " gated, " << acc.failed_triangulation << " failed triangulation)\n";
  if (req.opt.init.mode != ovton::msckf::InitMode::GroundTruth && !r.traj.empty() && !data.images.empty()) {
    const auto ic = ovton::eval::check_initialisation(r.traj.front(), data.groundtruth, data.images.front().t_cam_ns);
    if (ic.ok)
      std::cout << "initialisation vs ground truth: after " << ic.data_s << " s of images, roll/pitch error "
                << ic.tilt_err_deg << " deg, velocity error " << ic.vel_err_m_s << " m/s (true speed " << ic.speed_m_s
                << " m/s)\n";
  }
  if (tm.frames > 0)
    std::cout << "per frame [ms]: image load " << tm.image_load / tm.frames << ", tracking "
              << (tm.tracking + tm.tracking_thread) / tm.frames << (tm.tracking_thread > 0 ? " (own thread)" : "")
              << ", propagation " << tm.propagation / tm.frames << ", update " << tm.update / tm.frames << "; "
              << (r.play.wall_s > 0 ? r.play.data_span_s / r.play.wall_s : 0) << "x real time\n";
  if (!r.traj.empty())
    std::cout << "final t_d " << r.traj.back().td_s * 1e3 << " ms (sigma " << r.traj.back().td_sigma_s * 1e3
              << " ms)\n";
  if (!r.traj.empty())
    for (size_t k = 0; k < r.traj.back().cam_td_s.size(); ++k)
      std::cout << "final t_d of cam" << k + 1 << " " << r.traj.back().cam_td_s[k] * 1e3 << " ms (sigma "
                << r.traj.back().cam_td_sigma_s[k] * 1e3 << " ms)\n";
  if (!r.traj.empty())
    if (const std::string sw = ovton::msckf::describe_model_check(r.report.td_model, r.traj.front().t_ns, req.opt.td);
        !sw.empty())
      std::cout << sw << "\n";
  if (const std::string tpn = ovton::msckf::describe_tpn_learning(r.report.td_model, req.opt.ton.tpn.td_rate_max);
      !tpn.empty())
    std::cout << tpn << "\n";
  if (r.report.td_search && r.report.td_search->weak_excitation)
    std::cout << r.report.td_search->caution() << "\n";
  if (!nees_log.empty()) {
    std::ofstream out(nees_log);
    if (!out)
      throw ovton::core::DataError(nees_log, "cannot open for writing");
    out << "t_ns,nees_orientation,nees_position,nees_td\n";
    for (const auto &n : r.nees.per_frame)
      out << n.t_ns << ',' << n.ori << ',' << n.pos << ',' << n.td << '\n';
  }
  if (r.nees.count > 0) {
    std::cout << "NEES orientation " << r.nees.ori() << ", position " << r.nees.pos() << " (average over "
              << r.nees.count << " frames; 3 is ideal)";
    if (r.nees.td_count > 0)
      std::cout << ", t_d " << r.nees.td() << " (1 is ideal)";
    std::cout << "\n";
  }
  if (data.has_groundtruth() && r.traj.size() > 2) {
    try {
      const auto e = ovton::eval::evaluate(r.traj, data.groundtruth, data.td_truth, ovton::eval::EvalOptions{});
      std::cout << "APE " << e.ape_rmse_m << " m, ARE " << e.are_rmse_deg << " deg (posyaw, " << e.n_matched
                << " poses)";
      if (e.has_tpe)
        std::cout << ", TPE " << e.tpe_rmse_mm << " mm";
      std::cout << "\n";
    } catch (const ovton::core::UsageError &e) {
      std::cout << "evaluation skipped: " << e.what() << "\n";
    }
  }
  if (!req.mcap_out.empty()) {
    std::cout << "run recording: " << req.mcap_out << " (";
    for (size_t i = 0; i < r.mcap_counts.size(); ++i)
      std::cout << (i ? ", " : "") << r.mcap_counts[i].first << " " << r.mcap_counts[i].second;
    std::cout << " messages)\n";
  }
  std::cout << "trajectory: " << req.output << (r.play.interrupted ? " (interrupted; rows so far kept)" : "") << "\n";
  return r.play.interrupted ? 130 : 0;
}

} // namespace ovton::cli
