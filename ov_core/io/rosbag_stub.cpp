// Built instead of the rosbag reader and writer when ovton is configured with OVTON_WITH_ROSBAG=OFF.
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/io/rosbag_writer.h"
#include "ov_core/types/errors.h"

namespace ovton::core {

namespace {
[[noreturn]] void unsupported(const std::string &file) {
  throw UsageError(file + ": this ovton was built without ROS bag support (install librosbag-storage-dev and "
                          "libsensor-msgs-dev, then configure with -DOVTON_WITH_ROSBAG=ON)");
}
} // namespace

bool rosbag_supported() {
  return false;
}

Dataset load_bag(const std::string &file, const BagOptions &) {
  unsupported(file);
}

BagWriteReport write_bag(const Dataset &, const std::string &out, const BagWriteOptions &,
                         const std::function<bool(size_t, size_t)> &) {
  unsupported(out);
}

} // namespace ovton::core
