#include "ov_core/io/recording_export.h"
#include "ov_core/io/image_codecs.h"
#include "ov_core/io/image_store.h"
#include "ov_core/io/kalibr_writer.h"
#include "ov_core/types/errors.h"

#include <filesystem>

namespace fs = std::filesystem;

namespace ovton::core {

void walk_for_export(const Dataset &d, const std::function<void(const ImuData &)> &on_imu,
                     const std::function<void(const ImageEntry &, const cv::Mat &gray)> &on_image,
                     const std::function<bool(size_t, size_t)> &progress, const std::string &partial) {
  if (!d.images.empty() && d.images.front().features)
    throw UsageError(d.root + " is a feature-level dataset (cam0/features.csv): it has no images to export");
  size_t k = 0;
  for (size_t i = 0; i < d.images.size(); ++i) {
    const ImageEntry &e = d.images[i];
    for (; k < d.imu.size() && d.imu[k].t_imu_ns <= e.t_cam_ns; ++k)
      on_imu(d.imu[k]);
    const cv::Mat gray = load_image(e);
    if (gray.empty())
      throw DataError(e.path, "unreadable image (listed for stamp " + std::to_string(e.t_cam_ns) + ")");
    on_image(e, gray);
    if (progress && !progress(i + 1, d.images.size()))
      throw UsageError("export interrupted: " + partial + " left incomplete");
  }
  for (; k < d.imu.size(); ++k)
    on_imu(d.imu[k]);
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
                   const std::string &cam_topic, const std::string &imu_topic, BagWriteReport &rep) {
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
  write_kalibr_camchain(rep.camchain_file, d.cam, d.td_prior_s, cam_topic);
  write_kalibr_imu(rep.imu_file, d.imu_calib, imu_topic);
}

} // namespace ovton::core
