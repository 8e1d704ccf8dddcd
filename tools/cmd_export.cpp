// `ovton export --dataset DIR --out OUT.bag|OUT.mcap`: a dataset folder (real or simulated) or a recording as a ROS 1
// bag or a ROS 2 MCAP file, the forms ROS users record; the bag and MCAP tests replay them against the folder.
#include "ov_core/io/mcap_export.h"
#include "ov_core/io/recording_export.h"
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/io/rosbag_writer.h"
#include "ov_core/types/errors.h"
#include "tools/cli.h"
#include "tools/commands.h"
#include "tools/progress.h"

#include <boost/program_options.hpp>
#include <iostream>

namespace po = boost::program_options;

namespace ovton::cli {

namespace {

bool ends_with(const std::string &s, const std::string &tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

} // namespace

int cmd_export(const Args &args) {
  po::options_description desc(
      "ovton export: write a dataset folder or recording as a ROS 1 bag (sensor_msgs/Image mono8 + sensor_msgs/Imu, "
      "bag time = header stamp) or a ROS 2 MCAP file (sensor_msgs/msg/Image or CompressedImage, Imu, CameraInfo, "
      "/tf_static; log time = header stamp), and Kalibr files beside it");
  std::string dataset, out, format, compression, image_format = "raw";
  bool quiet = false, no_kalibr = false, no_summary = false;
  int jpeg_quality = 95;
  double chunk_kb = 1024;
  ovton::core::BagWriteOptions bag_opt;
  ovton::core::McapExportOptions mcap_opt;
  ovton::core::BagOptions in;
  desc.add_options()("help,h", "this help") //
      ("dataset,d", po::value(&dataset)->required(),
       "dataset folder (EuRoC, SCube or `ovton simulate` output), ROS bag, MCAP file or rosbag2 folder") //
      ("out,o", po::value(&out), "file to write (.bag or .mcap)")                                        //
      ("bag", po::value(&out), "same as --out (a .bag)")                                                 //
      ("format", po::value(&format), "bag or mcap (default: from the output's extension, else bag)")     //
      ("cam-topic", po::value(&bag_opt.cam_topic), "image topic to write (default /cam0/image_raw)")     //
      ("imu-topic", po::value(&bag_opt.imu_topic), "IMU topic to write (default /imu0)")                 //
      ("calib", po::value(&in.calib)->multitoken(),
       "when --dataset is a recording: its calibration (Kalibr files or an EuRoC folder), as for `run`") //
      ("compression", po::value(&compression),
       "bag: none (default), bz2 or lz4; mcap: zstd (default), lz4 or none (chunk compression)") //
      ("image-format", po::value(&image_format),
       "raw (mono8 sensor_msgs/Image, default), jpeg or png (sensor_msgs/CompressedImage on CAM_TOPIC/compressed)") //
      ("jpeg-quality", po::value(&jpeg_quality), "with --image-format jpeg: quality 1-100 (default 95)")            //
      ("chunk-kb", po::value(&chunk_kb), "mcap: chunk size in kB (default 1024)")                                   //
      ("no-summary", po::bool_switch(&no_summary),
       "mcap: no summary section or index (as a recorder that crashed leaves a file; for tests)") //
      ("no-kalibr", po::bool_switch(&no_kalibr),
       "do not write camchain-imucam-STEM.yaml and imu-STEM.yaml beside the output") //
      ("quiet,q", po::bool_switch(&quiet), "no progress bar");
  po::variables_map vm;
  if (!parse_command_line(args, desc, vm))
    return 0; // --help
  if (out.empty())
    throw ovton::core::UsageError("export: give the file to write with --out (or --bag)");
  if (format.empty())
    format = ends_with(out, ".mcap") ? "mcap" : "bag";
  if (format != "bag" && format != "mcap")
    throw ovton::core::UsageError("--format must be bag or mcap, not '" + format + "'");
  if (format == "bag" && (vm.count("chunk-kb") || no_summary))
    throw ovton::core::UsageError("--chunk-kb and --no-summary apply to --format mcap");
  if (!(chunk_kb >= 1 && chunk_kb <= 1024 * 1024))
    throw ovton::core::UsageError("--chunk-kb must be in [1, 1048576]");

  const ovton::core::Dataset d = ovton::core::load_recording(dataset, in);
  install_interrupt_handler();
  ProgressBar bar("export", quiet);
  const auto progress = [&](size_t i, size_t n) {
    bar.update(i, n, "");
    return !interrupted();
  };
  ovton::core::BagWriteReport rep;
  std::string cam_topic = bag_opt.cam_topic;
  if (format == "bag") {
    bag_opt.kalibr_files = !no_kalibr;
    if (!compression.empty())
      bag_opt.compression = compression;
    bag_opt.image_format = image_format;
    bag_opt.jpeg_quality = jpeg_quality;
    cam_topic = ovton::core::CompressedImageEncoder(image_format, jpeg_quality).topic(bag_opt.cam_topic);
    rep = ovton::core::write_bag(d, out, bag_opt, progress);
  } else {
    mcap_opt.cam_topic = bag_opt.cam_topic;
    mcap_opt.imu_topic = bag_opt.imu_topic;
    mcap_opt.image_format = image_format;
    mcap_opt.jpeg_quality = jpeg_quality;
    mcap_opt.kalibr_files = !no_kalibr;
    mcap_opt.mcap.compression = compression.empty() ? "zstd" : compression;
    mcap_opt.mcap.chunk_size = static_cast<size_t>(chunk_kb * 1024);
    mcap_opt.mcap.summary = !no_summary;
    cam_topic = ovton::core::mcap_export_cam_topic(mcap_opt);
    rep = ovton::core::write_mcap(d, out, mcap_opt, progress);
  }
  bar.finish();
  std::cout << format << ": " << out << " (" << rep.images << " images on " << cam_topic << ", " << rep.imu
            << " IMU readings on " << bag_opt.imu_topic << ", " << rep.bytes / 1e6 << " MB)\n";
  if (!no_kalibr)
    std::cout << "calibration: " << rep.camchain_file << ", " << rep.imu_file << "\n";
  return 0;
}

} // namespace ovton::cli
