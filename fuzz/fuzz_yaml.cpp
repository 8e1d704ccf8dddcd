// libFuzzer target: the YAML readers (EuRoC camera and IMU sensor.yaml, the estimator config).
#include "fuzz_util.h"
#include "ov_core/io/dataset.h"
#include "ov_msckf_ton/core/vio_options.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const std::string file = ovfuzz::write_file("config.yaml", std::string(reinterpret_cast<const char *>(data), size));
  ovfuzz::expect_clean([&] { ovton::core::load_euroc_camera_yaml(file); });
  ovfuzz::expect_clean([&] { ovton::core::load_euroc_imu_yaml(file); });
  ovfuzz::expect_clean([&] { ovton::msckf::load_vio_options(file); });
  return 0;
}
