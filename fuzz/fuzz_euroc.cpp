// libFuzzer target: a whole EuRoC folder (cam0/data.csv, imu0/data.csv, ground truth, the two sensor.yaml files,
// parts separated by "\n%%\n") loaded, and every image stamp taken to the IMU clock as the estimator does, so that
// stamps reach the time arithmetic too.
#include "fuzz_util.h"
#include "ov_core/io/dataset.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const auto parts = ovfuzz::split_parts(data, size, 5);
  const char *files[] = {"mav0/cam0/data.csv", "mav0/imu0/data.csv", "mav0/state_groundtruth_estimate0/data.csv",
                         "mav0/cam0/sensor.yaml", "mav0/imu0/sensor.yaml"};
  std::filesystem::remove_all(ovfuzz::scratch() / "mav0");
  for (size_t i = 0; i < parts.size(); ++i)
    ovfuzz::write_file(files[i], parts[i]);
  ovfuzz::expect_clean([&] {
    ovton::core::LoadOptions lo;
    lo.check_images_exist = false;
    const ovton::core::Dataset d = ovton::core::load_euroc(ovfuzz::scratch().string(), lo);
    for (double td : {0.0, 0.2, -0.2})
      for (const auto &e : d.images)
        (void)ovton::core::try_imu_time_ns(e.t_cam_ns, td);
  });
  return 0;
}
