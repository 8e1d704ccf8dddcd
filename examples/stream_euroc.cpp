// A robot program's view of ovton: sensors arrive one message at a time, in the order the drivers deliver them, and
// the estimator hands back poses and the camera-IMU time offset. Here the "drivers" are an EuRoC folder replayed
// with delivery jitter (images 0-80 ms late, the IMU in bursts of 8 readings up to 30 ms late), so images often
// arrive before the IMU readings that cover them; the estimator sorts that out and gives the same trajectory as
// `ovton run` on the folder (scripts/check_install.sh compares them byte for byte).
//   stream_euroc DATASET CONFIG.yaml OUT.csv     (OUT.csv in `ovton run`'s columns)
#include "ov_core/io/image_io.h"
#include "ov_core/io/rosbag_reader.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_msckf_ton/estimator/dataset_player.h"
#include "ov_msckf_ton/estimator/estimator.h"

#include <algorithm>
#include <cstdio>
#include <exception>
#include <random>
#include <vector>

int main(int argc, char **argv) try {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s DATASET CONFIG.yaml OUT.csv\n", argv[0]);
    return 2;
  }
  const ovton::core::Dataset data = ovton::core::load_recording(argv[1], {});
  ovton::msckf::VioOptions opt = ovton::msckf::load_vio_options(argv[2]);
  ovton::apply_dataset_defaults(data, false, opt);
  ovton::Estimator estimator(ovton::setup_for(data, opt)); // calibration, and ground truth if the config asks for it

  ovton::core::TrajectoryWriter out(argv[3], ovton::core::TrajectoryFormat::Csv);
  estimator.add_state_callback([&](const ovton::core::StateSample &s) {
    out.write(s);                    // on the estimator's thread, as each state comes out
    if (s.t_ns / 50000000 % 20 == 0) // about once a second
      std::printf("t %.3f s  p [%.3f %.3f %.3f] m  t_d %.2f +- %.2f ms\n", s.t_ns * 1e-9, s.p.x(), s.p.y(), s.p.z(),
                  s.td_s * 1e3, s.td_sigma_s * 1e3);
  });

  // The drivers: every message with the time it reaches this program.
  struct Message {
    int64_t arrival_ns;
    bool image;
    size_t index;
  };
  std::vector<Message> inbox;
  std::mt19937 rng(42);
  std::uniform_int_distribution<int64_t> image_delay(0, 80000000), imu_delay(0, 30000000);
  int64_t previous = 0; // a driver delivers its messages in order
  for (size_t i = 0; i < data.imu.size(); i += 8) {
    const size_t last = std::min(i + 7, data.imu.size() - 1);
    previous = std::max(previous, data.imu[last].t_imu_ns + imu_delay(rng));
    for (size_t k = i; k <= last; ++k)
      inbox.push_back({previous, false, k});
  }
  previous = 0;
  for (size_t i = 0; i < data.images.size(); ++i)
    inbox.push_back({previous = std::max(previous, data.images[i].t_cam_ns + image_delay(rng)), true, i});
  std::stable_sort(inbox.begin(), inbox.end(),
                   [](const Message &a, const Message &b) { return a.arrival_ns < b.arrival_ns; });

  for (const Message &m : inbox) {
    if (!m.image) {
      estimator.feed_imu(data.imu[m.index]);
      continue;
    }
    const ovton::core::ImageEntry &e = data.images[m.index];
    if (e.features) // a feature-level recording: points instead of pixels
      estimator.feed_features(e.t_cam_ns, *e.features);
    else
      estimator.feed_image(e.t_cam_ns, ovton::core::load_gray_image(e, data.cam.width, data.cam.height));
  }
  estimator.finish();
  const ovton::EstimatorStatus st = estimator.status();
  std::printf("%ld states; final t_d %.2f +- %.2f ms; %s\n", st.states_out, st.td_s * 1e3, st.td_sigma_s * 1e3,
              st.init_message.c_str());
  return 0;
} catch (const std::exception &e) {
  std::fprintf(stderr, "stream_euroc: %s\n", e.what());
  return 1;
}
