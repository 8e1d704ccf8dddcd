#include "ov_core/io/recording_export.h"
#include "ov_core/io/image_codecs.h"
#include "ov_core/io/image_store.h"
#include "ov_core/io/kalibr_writer.h"
#include "ov_core/types/errors.h"

#include <climits>
#include <filesystem>

namespace fs = std::filesystem;

namespace ovton::core {

void walk_for_export(const Dataset &d, const std::function<void(const ImuData &)> &on_imu,
                     const std::function<void(const ImageEntry &, const cv::Mat &gray, size_t camera)> &on_image,
                     const std::function<bool(size_t, size_t)> &progress, const std::string &partial) {
  if (!d.images.empty() && d.images.front().features)
    throw UsageError(d.root + " is a feature-level dataset (cam0/features.csv): it has no images to export");
  const auto write = [&](const ImageEntry &e, size_t camera) {
    const cv::Mat gray = load_image(e);
    if (gray.empty())
      throw DataError(e.path, "unreadable image (listed for stamp " + std::to_string(e.t_cam_ns) + ")");
    on_image(e, gray, camera);
  };
  std::vector<size_t> next(d.more_cameras.size(), 0); // each further camera's first image not yet written
  const auto write_more = [&](int64_t until_ns) {
    for (size_t c = 0; c < next.size(); ++c)
      for (const auto &imgs = d.more_cameras[c].images; next[c] < imgs.size() && imgs[next[c]].t_cam_ns <= until_ns;)
        write(imgs[next[c]++], c + 1);
  };
  size_t k = 0;
  for (size_t i = 0; i < d.images.size(); ++i) {
    const ImageEntry &e = d.images[i];
    for (; k < d.imu.size() && d.imu[k].t_imu_ns <= e.t_cam_ns; ++k)
      on_imu(d.imu[k]);
    write(e, 0);
    write_more(e.t_cam_ns);
    if (progress && !progress(i + 1, d.images.size()))
      throw UsageError("export interrupted: " + partial + " left incomplete");
  }
  for (; k < d.imu.size(); ++k)
    on_imu(d.imu[k]);
  write_more(INT64_MAX);
}

std::string export_camera_topic(const std::string &cam0_topic, size_t k) {
  if (k == 0)
    return cam0_topic;
  const std::string cam = "cam" + std::to_string(k);
  const size_t at = cam0_topic.find("cam0");
  return at == std::string::npos ? cam0_topic + "_" + cam : std::string(cam0_topic).replace(at, 4, cam);
}

CompressedImageEncoder::CompressedImageEncoder(const std::string &format, int jpeg_quality)
    : format_(format), quality_(jpeg_quality) {
  if (format != "raw" && format != "jpeg" && format != "png")
    throw UsageError("unknown image format '" + format + "' (expected raw, jpeg or png)");
  if (jpeg_quality < 1 || jpeg_quality > 100)
    throw UsageError("JPEG quality " + std::to_string(jpeg_quality) + " is not in 1..100");
}

std::vector<uint8_t> CompressedImageEncoder::encode(const cv::Mat &gray, const std::string &path) const {
  std::vector<int> params;
  if (format_ == "jpeg")
    params = {jpeg_quality_param(), quality_};
  std::vector<uchar> bytes;
  if (!encode_image(format_ == "jpeg" ? ".jpg" : ".png", gray, bytes, params))
    throw DataError(path, "cannot be encoded as " + format_);
  return bytes;
}

void finish_export(const std::string &partial, const std::string &out, const Dataset &d, bool kalibr,
                   const std::vector<std::string> &cam_topics, const std::string &imu_topic, BagWriteReport &rep) {
  std::error_code ec;
  fs::rename(partial, out, ec);
  if (ec)
    throw DataError(out, "cannot rename " + partial + " to it: " + ec.message());
  rep.bytes = fs::file_size(out, ec);
  if (!kalibr)
    return;
  const fs::path p(out);
  const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  rep.camchain_file = (dir / ("camchain-imucam-" + p.stem().string() + ".yaml")).string();
  rep.imu_file = (dir / ("imu-" + p.stem().string() + ".yaml")).string();
  std::vector<CameraCalib> cams = {d.cam};
  for (const CameraStream &c : d.more_cameras)
    cams.push_back(c.cam);
  write_kalibr_rig(rep.camchain_file, cams, d.td_prior_s, cam_topics);
  write_kalibr_imu(rep.imu_file, d.imu_calib, imu_topic);
}

} // namespace ovton::core
