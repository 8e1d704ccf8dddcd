// `ovton benchmark`: per-frame cost by stage, throughput as a multiple of real time, and resident memory over a run,
// for one or more time-offset modes replayed one after another in this process (see docs/benchmarks.md).
#include "ov_core/io/dataset.h"
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/io/text_format.h"
#include "ov_core/types/errors.h"
#include "ov_sim/simulator.h"
#include "tools/cli.h"
#include "tools/commands.h"
#include "tools/compare_report.h"
#include "tools/mem_usage.h"
#include "tools/progress.h"
#include "tools/run_pipeline.h"

#include <algorithm>
#include <array>
#include <boost/program_options.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <opencv2/core.hpp>
#include <sstream>
#include <thread>

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace ovton::cli {

namespace {

/// What one mode's run left behind; the trajectory itself is dropped so it does not weigh on the next mode's RSS.
struct ModeBench {
  std::string mode;
  long images = 0, images_before_init = 0, updates = 0, features_used = 0;
  double data_span_s = 0, wall_s = 0;
  // Mean cost per processed image [ms]. `other` is what the stage clocks do not see: IMU hand-over, replay,
  // trajectory output and the progress bar; total = wall / images, so the columns add up.
  double load = 0, track = 0, prop = 0, update = 0, nets = 0, other = 0, total = 0;
  /// With --prefetch the tracking thread's time per image [ms]; not in `total`.
  double track_thread = 0;
  /// From an image's feed to its state out [ms], median and 99th percentile (the streaming API's latency).
  double latency_p50 = 0, latency_p99 = 0;
  /// Process CPU time (user + system) per image [ms]: what a loaded, shared machine distorts least; with
  /// --prefetch it includes the decoding and tracking threads.
  double cpu = 0;
  std::array<double, 4> rss_quarter{}; ///< RSS [MB] at 25/50/75/100 % of the images
  double rss_start = 0, peak = 0;
  bool peak_own = false; ///< peak belongs to this mode alone (kernel mark was reset before it)
  bool interrupted = false;
  std::string init_message;

  double realtime() const { return wall_s > 0 ? data_span_s / wall_s : 0.0; }
  double features_per_frame() const { return images > 0 ? static_cast<double>(features_used) / images : 0.0; }
};

double percentile(std::vector<double> v, double q) {
  if (v.empty())
    return std::nan("");
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

std::string loadavg() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  if (!(f >> a >> b >> c))
    return "n/a";
  return a + " " + b + " " + c;
}

std::string num(double v, int prec = 3) {
  if (!std::isfinite(v))
    return "null";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.*f", prec, v);
  return buf;
}

/// Renders a 30 s (by default) flight along the built-in trajectory, or reuses one already in `dir`: rendering costs
/// far more than the benchmark itself, and the same seed gives the same bytes anyway.
void generate(const std::string &dir, double seconds, bool quiet) {
  if (fs::exists(fs::path(dir) / "mav0" / "cam0" / "data.csv")) {
    std::cerr << "benchmark: reusing the dataset in " << dir << " (delete it to render a new one)\n";
    return;
  }
  ovton::sim::SimOptions o;
  o.out_dir = dir;
  o.duration_s = seconds;
  std::string last_stage;
  size_t last_pct = 101;
  const auto rep = ovton::sim::write_simulation(o, [&](const std::string &stage, size_t done, size_t total) {
    if (quiet || total == 0)
      return;
    const size_t pct = done * 100 / total;
    if (stage != last_stage || pct != last_pct) {
      std::fprintf(stderr, "\rgenerate %-12s %3zu %%", stage.c_str(), pct);
      if (done == total)
        std::fprintf(stderr, "\n");
      last_stage = stage;
      last_pct = pct;
    }
  });
  std::cerr << "benchmark: rendered " << rep.n_images << " images, " << rep.n_imu << " IMU readings along "
            << rep.trajectory << " into " << dir << " in " << num(rep.total_seconds, 1) << " s\n";
}

ModeBench bench_mode(const ovton::core::Dataset &data, RunRequest req, const std::string &mode) {
  ModeBench b;
  b.mode = mode;
  ovton::msckf::apply_mode_spec(ovton::msckf::parse_mode_spec(mode), req.opt);
  req.label = "benchmark " + mode;

  b.peak_own = reset_peak_rss();
  b.rss_start = current_rss_mb();
  // The kernel may keep an older high-water mark in getrusage (e.g. after a thread exit); then the reset did not
  // reach what we read and the peak is the process's.
  if (b.peak_own && peak_rss_mb() > b.rss_start + 1.0)
    b.peak_own = false;

  const size_t n_all = data.images.size();
  const size_t n_run = req.max_images > 0 ? std::min(n_all, static_cast<size_t>(req.max_images)) : n_all;
  std::array<size_t, 4> at{};
  for (size_t q = 0; q < 4; ++q)
    at[q] = std::max<size_t>(1, (n_run * (q + 1) + 3) / 4);
  std::array<bool, 4> taken{};
  b.rss_quarter.fill(std::nan(""));
  double last_rss = std::nan("");
  req.on_progress = [&](size_t i, size_t) {
    // Reading statm costs a few microseconds against a frame of milliseconds; it gives an interrupted or short
    // replay an honest last sample taken while the estimator is still alive.
    last_rss = current_rss_mb();
    for (size_t q = 0; q < 4; ++q)
      if (!taken[q] && i >= at[q]) {
        b.rss_quarter[q] = last_rss;
        taken[q] = true;
      }
  };

  const double cpu0 = process_cpu_s();
  const RunResult r = run_dataset(data, req);
  const double cpu_s = process_cpu_s() - cpu0;
  // A replay can end short of n_run (interrupted, images beyond the IMU log): the 100 % column is then its last frame.
  if (!taken[3])
    b.rss_quarter[3] = last_rss;
  // ru_maxrss is in kB and the samples in pages: keep the peak from reading below a sample by rounding.
  b.peak = peak_rss_mb();
  for (double v : b.rss_quarter)
    if (std::isfinite(v))
      b.peak = std::max(b.peak, v);

  const auto &c = r.report.counters;
  const auto &t = r.report.times;
  b.images = c.images;
  b.images_before_init = c.images_before_init;
  b.updates = c.updates;
  b.features_used = c.features_used;
  b.data_span_s = r.play.data_span_s;
  b.wall_s = r.play.wall_s;
  b.interrupted = r.play.interrupted;
  b.init_message = r.report.init_message;
  b.latency_p50 = percentile(r.report.latency_ms, 0.5);
  b.latency_p99 = percentile(r.report.latency_ms, 0.99);
  if (b.images > 0) {
    const double n = static_cast<double>(b.images);
    b.load = r.play.decode_ms / n;
    b.track = t.tracking / n;
    b.track_thread = t.tracking_thread / n;
    b.prop = t.propagation / n;
    b.update = t.update / n;
    b.nets = t.networks / n;
    b.total = r.play.wall_s * 1e3 / n;
    b.cpu = cpu_s * 1e3 / n;
    b.other = b.total - (b.load + b.track + b.prop + b.update + b.nets);
  }
  return b;
}

void print_tables(const std::vector<ModeBench> &res, std::ostream &os) {
  char line[256];
  os << "\nper-frame cost [ms], mean over the images processed (stage clocks of VioManager; total = wall / images;\n"
        "x realtm = data span / wall; feat/frame = features used by MSCKF updates per image)\n";
  std::snprintf(line, sizeof(line), "%-7s %6s %7s %7s %7s %7s %7s %7s %7s %9s %8s %7s %9s %10s\n", "mode", "images",
                "load", "track", "prop", "update", "nets", "other", "total", "x realtm", "x first", "cpu", "cpu/first",
                "feat/frame");
  os << line;
  for (const auto &b : res) {
    std::snprintf(line, sizeof(line),
                  "%-7s %6ld %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f %9.1f %8.2f %7.2f %9.2f %10.1f\n",
                  b.mode.c_str(), b.images, b.load, b.track, b.prop, b.update, b.nets, b.other, b.total, b.realtime(),
                  res.front().total > 0 ? b.total / res.front().total : 0.0, b.cpu,
                  res.front().cpu > 0 ? b.cpu / res.front().cpu : 0.0, b.features_per_frame());
    os << line;
  }
  os << "cpu = process CPU time per image [ms] (user + system); cpu/first: its ratio to the first mode's\n";
  os << "latency [ms] from an image's feed to its state out (the streaming API's; with the coarse t_d search it "
        "includes the images held while it decides):";
  for (const auto &b : res)
    os << " " << b.mode << " p50 " << num(b.latency_p50, 2) << ", p99 " << num(b.latency_p99, 2) << ";";
  os << "\n";
  os << "\nresident memory [MB] at 25/50/75/100 % of the images; growth = 100 % - 25 %\n";
  std::snprintf(line, sizeof(line), "%-7s %8s %8s %8s %8s %8s %8s %8s\n", "mode", "start", "25%", "50%", "75%", "100%",
                "peak", "growth");
  os << line;
  bool any_process_peak = false;
  for (const auto &b : res) {
    any_process_peak |= !b.peak_own;
    std::snprintf(line, sizeof(line), "%-7s %8.1f %8.1f %8.1f %8.1f %8.1f %7.1f%s %8.1f\n", b.mode.c_str(), b.rss_start,
                  b.rss_quarter[0], b.rss_quarter[1], b.rss_quarter[2], b.rss_quarter[3], b.peak,
                  b.peak_own ? " " : "*", b.rss_quarter[3] - b.rss_quarter[0]);
    os << line;
  }
  if (any_process_peak)
    os << "* peak of the whole process so far (the kernel's high-water mark could not be reset for this mode)\n";
  if (res.size() > 1)
    os << "Modes after the first ran after it in the same process, on the same data already in memory and under the "
          "same machine load: read the 'x first' column as a ratio measured in the same run, not as an absolute.\n";
  for (const auto &b : res) {
    if (b.images_before_init > 0)
      os << b.mode << ": " << b.images_before_init << " of " << b.images
         << " images came before initialisation (load and tracking only)\n";
    if (b.track_thread > 0)
      os << b.mode << ": tracking ran on its own thread, " << b.track_thread << " ms/image there (not in total)\n";
    if (b.interrupted)
      os << b.mode << ": interrupted; numbers cover the images processed\n";
  }
}

void write_json(const std::string &file, const std::vector<ModeBench> &res, const std::string &dataset,
                const std::string &config, const std::string &init, const std::string &load_start,
                const std::string &load_end) {
  std::ofstream out(file);
  if (!out)
    throw ovton::core::UsageError("cannot write " + file);
  out << "{\n  \"dataset\": " << ovton::core::json_string(dataset)
      << ",\n  \"config\": " << ovton::core::json_string(config) << ",\n  \"init\": " << ovton::core::json_string(init)
      << ",\n  \"cores\": " << std::thread::hardware_concurrency()
      << ",\n  \"loadavg_start\": " << ovton::core::json_string(load_start)
      << ",\n  \"loadavg_end\": " << ovton::core::json_string(load_end)
      << ",\n  \"same_process\": true,\n  \"modes\": [";
  for (size_t i = 0; i < res.size(); ++i) {
    const auto &b = res[i];
    out << (i ? "," : "") << "\n    {\"mode\": " << ovton::core::json_string(b.mode) << ", \"images\": " << b.images
        << ", \"images_before_init\": " << b.images_before_init << ", \"updates\": " << b.updates
        << ", \"features_used\": " << b.features_used << ", \"features_per_frame\": " << num(b.features_per_frame())
        << ",\n     \"data_span_s\": " << num(b.data_span_s) << ", \"wall_s\": " << num(b.wall_s)
        << ", \"realtime_factor\": " << num(b.realtime())
        << ", \"ratio_to_first\": " << num(res.front().total > 0 ? b.total / res.front().total : NAN)
        << ",\n     \"ms_per_frame\": {\"image_load\": " << num(b.load, 4) << ", \"tracking\": " << num(b.track, 4)
        << ", \"tracking_thread\": " << num(b.track_thread, 4) << ", \"propagation\": " << num(b.prop, 4)
        << ", \"update\": " << num(b.update, 4) << ", \"networks\": " << num(b.nets, 4)
        << ", \"other\": " << num(b.other, 4) << ", \"total\": " << num(b.total, 4) << ", \"cpu\": " << num(b.cpu, 4)
        << "},\n     \"latency_ms\": {\"p50\": " << num(b.latency_p50, 3) << ", \"p99\": " << num(b.latency_p99, 3)
        << "},\n     \"rss_mb\": {\"start\": " << num(b.rss_start, 2) << ", \"p25\": " << num(b.rss_quarter[0], 2)
        << ", \"p50\": " << num(b.rss_quarter[1], 2) << ", \"p75\": " << num(b.rss_quarter[2], 2)
        << ", \"p100\": " << num(b.rss_quarter[3], 2) << ", \"peak\": " << num(b.peak, 2)
        << ", \"peak_scope\": " << ovton::core::json_string(b.peak_own ? "mode" : "process")
        << "},\n     \"interrupted\": " << (b.interrupted ? "true" : "false") << "}";
  }
  out << "\n  ]\n}\n";
  out.close();
  if (!out)
    throw ovton::core::UsageError("failed writing " + file);
}

} // namespace

int cmd_benchmark(const Args &args) {
  po::options_description desc(
      "ovton benchmark: per-frame cost by stage, x real time and resident memory, mode after mode on one thread");
  std::string config, dataset, generate_dir, modes_str = "sr", init, json;
  double gen_seconds = 30.0;
  bool quiet = false, threaded = false, realtime = false;
  RunRequest req;
  desc.add_options()("help,h", "this help")                                                                         //
      ("dataset,d", po::value(&dataset), "dataset folder (EuRoC or SCube), ROS 1 bag, MCAP file or rosbag2 folder") //
      ("generate", po::value(&generate_dir), "without --dataset: render a built-in flight here and benchmark it")   //
      ("generate-seconds", po::value(&gen_seconds), "length of the --generate flight [s] (default 30)")             //
      ("config,c", po::value(&config), "estimator config YAML (default: built-in defaults)")                        //
      ("modes,m", po::value(&modes_str), "comma-separated td modes, run in this order (default sr)")                //
      ("init", po::value(&init),
       "static|groundtruth|auto|dynamic (overrides the config; groundtruth with --generate)") //
      ("max-images", po::value(&req.max_images), "stop each mode after this many images")     //
      ("json", po::value(&json), "also write the numbers as JSON")                            //
      ("realtime", po::bool_switch(&realtime),
       "feed the recording at its own pace, as sensors deliver it: the latency line is then a live system's (the "
       "cost columns still hold; x realtm is 1)") //
      ("prefetch", po::bool_switch(&threaded),
       "track and filter on threads of their own while the next image is decoded (as `ovton run` does)") //
      ("quiet,q", po::bool_switch(&quiet), "no progress bars");
  ovton::core::BagOptions bag_opt;
  add_bag_options(desc, bag_opt);
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0; // --help
  req.threaded = threaded;
  req.pace = realtime ? 1.0 : 0.0;
  if (dataset.empty() && generate_dir.empty())
    throw ovton::core::UsageError("give --dataset DIR, or --generate DIR to render a dataset to benchmark");
  if (!dataset.empty() && !generate_dir.empty())
    throw ovton::core::UsageError("--dataset and --generate are exclusive");
  if (!(gen_seconds > 0))
    throw ovton::core::UsageError("--generate-seconds must be positive");
  if (!init.empty())
    ovton::msckf::parse_init_mode(init); // fail before any work on a typo
  std::vector<std::string> modes;        // fail before any work on a typo
  for (const auto &spec : parse_compare_modes(modes_str))
    modes.push_back(spec.name);

  req.opt = config.empty() ? ovton::msckf::VioOptions{} : ovton::msckf::load_vio_options(config);
  if (!generate_dir.empty()) {
    // The built-in flight starts moving: a static initialisation would never succeed.
    if (init.empty())
      init = "groundtruth";
    generate(generate_dir, gen_seconds, quiet);
    dataset = generate_dir;
  }
  if (!init.empty())
    req.opt.init.mode = ovton::msckf::parse_init_mode(init);
  req.progress = !quiet;

  // One thread, so that the numbers say what one core does and modes do not compete with each other.
  cv::setNumThreads(0);

  const ovton::core::Dataset data = ovton::core::load_recording(dataset, bag_opt);
  ovton::apply_dataset_defaults(data, false, req.opt);
  const std::string load_start = loadavg();
  std::cout << "dataset " << dataset << ": " << data.images.size() << " images " << data.cam.width << "x"
            << data.cam.height << ", " << data.imu.size() << " IMU readings; init "
            << ovton::msckf::to_string(req.opt.init.mode) << "; config "
            << (config.empty() ? "built-in defaults" : config) << "\nmachine: " << std::thread::hardware_concurrency()
            << " cores, load average " << load_start << "; "
            << (req.threaded ? "image decoding (main thread) + tracking thread + filter thread" : "one thread")
            << " per mode, modes run one after another\n"
            << std::flush;

  // The JSON is rewritten after every mode, so an interrupted or failing benchmark keeps the modes already done;
  // writing it once before the first mode finds an unwritable path before minutes of work.
  const std::string init_name = ovton::msckf::to_string(req.opt.init.mode);
  std::vector<ModeBench> res;
  const auto save = [&] {
    if (!json.empty())
      write_json(json, res, dataset, config, init_name, load_start, loadavg());
  };
  save();
  install_interrupt_handler();
  for (const auto &m : modes) {
    res.push_back(bench_mode(data, req, m));
    save();
    if (!quiet)
      std::cerr << m << ": " << res.back().init_message << "\n";
    if (res.back().interrupted)
      break;
  }
  print_tables(res, std::cout);
  std::cout << "load average at the end: " << loadavg() << "\n";
  if (!json.empty())
    std::cout << "json: " << json << "\n";
  return res.back().interrupted ? 130 : 0;
}

} // namespace ovton::cli
