// `ovton info --dataset DIR|BAG`: load and validate a dataset folder or ROS bag, print what it holds; --td-search also
// runs the coarse camera-IMU offset search that `run` starts the filter with.
#include "ov_core/io/dataset.h"
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/init/td_search.h"
#include "tools/cli.h"
#include "tools/commands.h"

#include <boost/program_options.hpp>
#include <cmath>
#include <iomanip>
#include <iostream>

namespace po = boost::program_options;

namespace ovton::cli {

int cmd_info(const Args &args) {
  po::options_description desc(
      "ovton info: load a dataset folder (EuRoC or SCube) or ROS bag, validate it, summarise it");
  std::string dir;
  double prior_ms = 0.0, range_ms = 200.0;
  desc.add_options()("help,h", "this help")("dataset,d", po::value(&dir)->required(),
                                            "dataset folder, ROS 1 bag, MCAP file or rosbag2 folder")  //
      ("td-search", "also search the camera-IMU time offset (images' rotation rate against the gyro)") //
      ("td-init-ms", po::value(&prior_ms), "centre of the search [ms] (default: the dataset's prior, else 0)")(
          "td-range-ms", po::value(&range_ms), "half width of the search [ms] (default 200)");
  ovton::core::BagOptions bag_opt;
  add_bag_options(desc, bag_opt);
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0; // --help

  const ovton::core::Dataset d = ovton::core::load_recording(dir, bag_opt);
  const double t0 = ovton::core::ns_to_s(d.images.front().t_cam_ns),
               t1 = ovton::core::ns_to_s(d.images.back().t_cam_ns);
  std::cout << std::fixed << std::setprecision(3);
  std::cout << "dataset      " << d.root << " (" << d.kind << ")\n"
            << "images       " << d.images.size() << " over " << (t1 - t0) << " s, " << d.cam.width << "x"
            << d.cam.height << " @ " << d.cam.rate_hz << " Hz\n"
            << "imu          " << d.imu.size() << " readings over "
            << ovton::core::ns_to_s(d.imu.back().t_imu_ns - d.imu.front().t_imu_ns) << " s @ " << d.imu_calib.rate_hz
            << " Hz\n"
            << "intrinsics   " << d.cam.intrinsics.transpose() << "\n"
            << std::setprecision(8) << "distortion   " << to_string(d.cam.distortion) << " "
            << d.cam.dist_coeffs.transpose() << "\n"
            << "T_BC\n"
            << d.cam.T_BC << "\n"
            << std::setprecision(3) << "groundtruth  "
            << (d.has_groundtruth() ? std::to_string(d.groundtruth.size()) + " rows" +
                                          (d.groundtruth.front().has_orientation ? "" : " (position only)")
                                    : std::string("none"))
            << "\n"
            << "td_truth     " << (d.has_td_truth() ? std::to_string(d.td_truth.size()) + " rows" : std::string("none"))
            << "\n";
  if (vm.count("td-search")) {
    if (!(range_ms > 0 && range_ms <= 1000) || !(std::abs(prior_ms) <= 10000))
      throw ovton::core::UsageError("--td-range-ms must be in (0, 1000] and --td-init-ms within +-10000");
    ovton::msckf::TdSearchOptions so;
    so.range_s = range_ms * 1e-3;
    const auto r =
        ovton::msckf::search_td(d.images, d.imu, d.cam, vm.count("td-init-ms") ? prior_ms * 1e-3 : d.td_prior_s, so);
    std::cout << "t_d search   " << r.summary() << "\n";
    if (!r.found && r.pairs > 0)
      std::cout << "             best candidate " << r.td_s * 1e3 << " ms, sigma " << r.sigma_s * 1e3 << " ms\n";
  }
  if (!d.notes.empty())
    std::cout << "read         " << d.notes << "\n";
  for (const std::string &w : d.warnings)
    std::cout << "warning      " << w << "\n";
  return 0;
}

} // namespace ovton::cli
