// libFuzzer target: an MCAP file (chunks in every compression, records, CDR messages) through the low-level walk with
// every message decoded by its schema, then as a recording, calibrated by a folder and by its own CameraInfo and
// /tf_static, its images read and replayed.
#include "ov_core/io/mcap_reader.h"
#include "ov_core/io/ros2_messages.h"
#include "ov_core/io/ros2_reader.h"
#include "recording_fuzz_util.h"

#include <map>

namespace {

void decode(ovton::core::Ros2Type type, const ovton::core::McapMessage &m, const std::string &file) {
  using namespace ovton::core;
  switch (type) {
  case Ros2Type::Image: {
    const Ros2Image img = decode_ros2_image(m.data, m.size, file, "w");
    raw_image_to_gray(img.pixels, file, "w");
    break;
  }
  case Ros2Type::CompressedImage: {
    const Ros2CompressedImage img = decode_ros2_compressed_image(m.data, m.size, file, "w");
    compressed_image_size(img.data.data, img.data.size);
    break;
  }
  case Ros2Type::Imu:
    decode_ros2_imu(m.data, m.size, file, "w");
    break;
  case Ros2Type::CameraInfo:
    camera_from_info(decode_ros2_camera_info(m.data, m.size, file, "w"), Eigen::Matrix4d::Identity(), file, "w");
    break;
  case Ros2Type::TfMessage:
    decode_ros2_tf(m.data, m.size, file, "w");
    break;
  default:
    break;
  }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const std::string file = ovfuzz::write_file("in.mcap", std::string(reinterpret_cast<const char *>(data), size));
  ovfuzz::expect_clean([&] {
    ovton::core::McapReader r(file);
    std::map<uint16_t, ovton::core::Ros2Type> types;
    std::vector<ovton::core::McapMessageRef> refs;
    r.scan([&](const ovton::core::McapChannel &c) { types[c.id] = ovton::core::ros2_type(c.schema_name); },
           [&](const ovton::core::McapMessage &m) {
             refs.push_back(m.ref);
             ovfuzz::expect_clean([&] { decode(types[m.channel_id], m, file); });
           });
    for (size_t i = 0; i < refs.size() && i < 8; ++i)
      r.fetch(refs[refs.size() - 1 - i]); // backwards: another chunk each time
  });
  for (const bool calibrated : {true, false})
    ovfuzz::expect_clean([&] {
      ovton::core::BagOptions o;
      if (calibrated)
        o.calib = {ovfuzz::calibration_folder()};
      ovfuzz::read_all(ovton::core::load_mcap(file, o));
    });
  return 0;
}
