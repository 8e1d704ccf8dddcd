#include "ov_core/io/replay.h"
#include "ov_core/io/dataset.h"
#include "ov_core/types/errors.h"

#include <string>

namespace ovton::core {

ReplayStats Replay::run(ReplayConsumer &c, const std::function<bool(size_t, size_t)> &progress) const {
  ReplayStats st;
  size_t k = 0;
  for (size_t i = 0; i < images_.size(); ++i) {
    const ImageEntry &img = images_[i];
    const double td_s = c.td_for_image_s(img.t_cam_ns);
    const auto td_ns = try_s_to_ns(td_s);
    const auto t_imu = td_ns ? try_add_ns(img.t_cam_ns, *td_ns) : std::nullopt;
    if (!t_imu)
      throw UsageError("image " + img.path + " (stamp " + std::to_string(img.t_cam_ns) + " ns) with t_d " +
                       std::to_string(td_s) + " s has no IMU-clock time in the int64 ns clock");
    const int64_t t_imu_ns = *t_imu;
    // Feed every reading up to and including the image's IMU-clock time; one more if the image falls between two
    // readings, so the consumer can interpolate to the image time instead of extrapolating.
    const int64_t ahead = c.imu_lookahead_ns();
    while (k < imu_.size() && imu_[k].t_imu_ns <= t_imu_ns + ahead)
      c.on_imu(imu_[k++]);
    if (k < imu_.size() && (k == 0 || imu_[k - 1].t_imu_ns < t_imu_ns))
      c.on_imu(imu_[k++]);
    st.imu_fed = k;
    if (k == 0 || imu_[k - 1].t_imu_ns < t_imu_ns) {
      ++st.images_skipped; // no IMU covers this image: it cannot be used
    } else {
      c.on_image(img);
      ++st.images_fed;
    }
    if (progress && !progress(i + 1, images_.size()))
      return st;
  }
  if (dataset_ && !dataset_->truncated_file.empty())
    throw DataError(dataset_->truncated_file, dataset_->truncated_reason);
  return st;
}

} // namespace ovton::core
