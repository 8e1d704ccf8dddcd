// `ovton info --dataset DIR|BAG`: load and validate a dataset folder or ROS bag, print what it holds.
#include "ov_core/io/dataset.h"
#include "ov_core/io/rosbag_reader.h"
#include "tools/cli.h"
#include "tools/commands.h"

#include <boost/program_options.hpp>
#include <iomanip>
#include <iostream>

namespace po = boost::program_options;

namespace ovton {

int cmd_info(const Args &args) {
  po::options_description desc(
      "ovton info: load a dataset folder (EuRoC or SCube) or ROS bag, validate it, summarise it");
  std::string dir;
  desc.add_options()("help,h", "this help")("dataset,d", po::value(&dir)->required(),
                                            "dataset folder or ROS bag (.bag)");
  ov_core::BagOptions bag_opt;
  add_bag_options(desc, bag_opt);
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0; // --help

  const ov_core::Dataset d = ov_core::load_recording(dir, bag_opt);
  const double t0 = ov_core::ns_to_s(d.images.front().t_cam_ns), t1 = ov_core::ns_to_s(d.images.back().t_cam_ns);
  std::cout << std::fixed << std::setprecision(3);
  std::cout << "dataset      " << d.root << " (" << d.kind << ")\n"
            << "images       " << d.images.size() << " over " << (t1 - t0) << " s, " << d.cam.width << "x"
            << d.cam.height << " @ " << d.cam.rate_hz << " Hz\n"
            << "imu          " << d.imu.size() << " readings over "
            << ov_core::ns_to_s(d.imu.back().t_imu_ns - d.imu.front().t_imu_ns) << " s @ " << d.imu_calib.rate_hz
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
  if (!d.notes.empty())
    std::cout << "read         " << d.notes << "\n";
  return 0;
}

} // namespace ovton
