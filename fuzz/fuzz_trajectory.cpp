// libFuzzer target: trajectory files (project CSV, EuRoC ground truth, TUM text, position-only) and td_truth.
#include "fuzz_util.h"
#include "ov_core/io/trajectory_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const std::string file = ovfuzz::write_file("traj.txt", std::string(reinterpret_cast<const char *>(data), size));
  ovfuzz::expect_clean([&] {
    // Whatever is read must be writable again: the writer formats stamps and numbers the reader accepted.
    const auto traj = ovton::core::read_trajectory(file);
    ovton::core::TrajectoryWriter w((ovfuzz::scratch() / "out.txt").string(), ovton::core::TrajectoryFormat::Tum);
    for (const auto &s : traj)
      w.write(s);
  });
  ovfuzz::expect_clean([&] { ovton::core::read_td_truth(file); });
  return 0;
}
