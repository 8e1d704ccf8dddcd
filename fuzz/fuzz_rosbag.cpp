// libFuzzer target: a ROS 1 bag (raw or compressed images, IMU) through load_bag with a fixed calibration, its raw
// images read and replayed. The bag's records are parsed by Debian's rosbag storage library; what it throws must reach
// the user as a DataError naming the bag.
#include "ov_core/io/rosbag_reader.h"
#include "recording_fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const std::string file = ovfuzz::write_file("in.bag", std::string(reinterpret_cast<const char *>(data), size));
  ovfuzz::expect_clean([&] {
    ovton::core::BagOptions o;
    o.calib = {ovfuzz::calibration_folder()};
    ovfuzz::read_all(ovton::core::load_bag(file, o));
  });
  return 0;
}
