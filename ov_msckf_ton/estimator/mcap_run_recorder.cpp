#include "ov_msckf_ton/estimator/mcap_run_recorder.h"

namespace ovton {

namespace {

core::FeatureStatus status_of(msckf::FrameFeatures::Fate fate) {
  switch (fate) {
  case msckf::FrameFeatures::Used:
    return core::FeatureStatus::Used;
  case msckf::FrameFeatures::Gated:
    return core::FeatureStatus::Gated;
  default:
    return core::FeatureStatus::Tracked;
  }
}

} // namespace

McapRunRecorder::McapRunRecorder(const std::string &path, const core::RunMcapOptions &opt) : writer_(path, opt) {}

std::shared_ptr<McapRunRecorder> McapRunRecorder::attach(Estimator &est, const std::string &path,
                                                         const core::RunMcapOptions &opt) {
  auto rec = std::make_shared<McapRunRecorder>(path, opt);
  est.add_observer(rec);
  // The estimator keeps the recorder alive through its observer; the callback runs on the same (filter) thread.
  est.add_state_callback([r = rec.get()](const core::StateSample &s) { r->on_state(s); });
  return rec;
}

void McapRunRecorder::set_truth(std::vector<core::StateSample> groundtruth, std::vector<core::TdSample> td_truth) {
  writer_.set_truth(std::move(groundtruth), std::move(td_truth));
}

void McapRunRecorder::on_image(int64_t t_cam_ns, const cv::Mat &gray) {
  std::vector<uint8_t> message = writer_.encode_image(t_cam_ns, gray);
  const std::lock_guard<std::mutex> lk(pending_m_);
  pending_[t_cam_ns] = std::move(message);
}

void McapRunRecorder::on_frame(const msckf::FrameFeatures &frame) {
  std::vector<uint8_t> image; // stays empty for a feature-level image
  {
    const std::lock_guard<std::mutex> lk(pending_m_);
    // Images before this one that the filter did not process (before its initialisation, beyond the IMU) are dropped.
    pending_.erase(pending_.begin(), pending_.lower_bound(frame.t_cam_ns));
    const auto it = pending_.find(frame.t_cam_ns);
    if (it != pending_.end()) {
      image = std::move(it->second);
      pending_.erase(it);
    }
  }
  features_.resize(frame.ids.size());
  for (size_t i = 0; i < frame.ids.size(); ++i)
    features_[i] = {frame.ids[i], frame.uv[i], status_of(frame.fate[i])};
  writer_.add_encoded_image(frame.t_cam_ns, frame.t_imu_ns, image, features_);
}

void McapRunRecorder::on_state(const core::StateSample &s) {
  writer_.add_state(s);
}

void McapRunRecorder::close() {
  writer_.close();
  const std::lock_guard<std::mutex> lk(pending_m_);
  pending_.clear();
}

} // namespace ovton
