// `ovton export --dataset DIR --bag OUT.bag`: a dataset folder (real or simulated) as a ROS 1 bag, the form a ROS user
// records; the bag tests replay it against the folder.
#include "ov_core/io/dataset.h"
#include "ov_core/io/rosbag_writer.h"
#include "tools/cli.h"
#include "tools/commands.h"
#include "tools/progress.h"

#include <boost/program_options.hpp>
#include <iostream>

namespace po = boost::program_options;

namespace ovton::cli {

int cmd_export(const Args &args) {
  po::options_description desc("ovton export: write a dataset folder as a ROS 1 bag (sensor_msgs/Image mono8 + "
                               "sensor_msgs/Imu, bag time = header stamp) and Kalibr files beside it");
  std::string dataset, bag;
  bool quiet = false, no_kalibr = false;
  ovton::core::BagWriteOptions opt;
  desc.add_options()("help,h", "this help")                                                                      //
      ("dataset,d", po::value(&dataset)->required(), "dataset folder (EuRoC, SCube or `ovton simulate` output)") //
      ("bag,o", po::value(&bag)->required(), "bag file to write")                                                //
      ("cam-topic", po::value(&opt.cam_topic), "image topic (default /cam0/image_raw)")                          //
      ("imu-topic", po::value(&opt.imu_topic), "IMU topic (default /imu0)")                                      //
      ("compression", po::value(&opt.compression), "none (default), bz2 or lz4")                                 //
      ("no-kalibr", po::bool_switch(&no_kalibr),
       "do not write camchain-imucam-STEM.yaml and imu-STEM.yaml beside the bag") //
      ("quiet,q", po::bool_switch(&quiet), "no progress bar");
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0; // --help
  opt.kalibr_files = !no_kalibr;

  const ovton::core::Dataset d = ovton::core::load_dataset(dataset);
  install_interrupt_handler();
  ProgressBar bar("export", quiet);
  const auto rep = ovton::core::write_bag(d, bag, opt, [&](size_t i, size_t n) {
    bar.update(i, n, "");
    return !interrupted();
  });
  bar.finish();
  std::cout << "bag: " << bag << " (" << rep.images << " images on " << opt.cam_topic << ", " << rep.imu
            << " IMU readings on " << opt.imu_topic << ", " << rep.bytes / 1e6 << " MB)\n";
  if (opt.kalibr_files)
    std::cout << "calibration: " << rep.camchain_file << ", " << rep.imu_file << "\n";
  return 0;
}

} // namespace ovton::cli
