// libFuzzer target: a whole EuRoC folder (cam0/data.csv, imu0/data.csv, ground truth, the two sensor.yaml files,
// parts separated by "\n%%\n") loaded and replayed, so that stamps reach the time arithmetic of the replay too.
#include "fuzz_util.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/replay.h"

namespace {

class Sink : public ovton::core::ReplayConsumer {
public:
  explicit Sink(double td) : td_(td) {}
  void on_imu(const ovton::core::ImuData &) override {}
  void on_image(const ovton::core::ImageEntry &) override {}
  double td_for_image_s(int64_t) const override { return td_; }

private:
  double td_;
};

} // namespace

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
    for (double td : {0.0, 0.2, -0.2}) {
      Sink sink(td);
      ovton::core::Replay(d).run(sink);
    }
  });
  return 0;
}
