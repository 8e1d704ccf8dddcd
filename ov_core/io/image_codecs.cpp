#include "ov_core/io/image_codecs.h"
#include "ov_core/io/image_codecs_api.h"
#include "ov_core/io/png_gray.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>

namespace ovton::core {
namespace {

constexpr const char *kPluginFile = "libovton_imgcodecs.so";

// Where OVTON_IMGCODECS names it, next to the running binary (a copied build folder keeps working), where
// `cmake --install` puts it, then where this tree's build put it (a binary copied elsewhere alone, the test and fuzz
// executables in their own folders).
std::vector<std::string> plugin_candidates() {
  std::vector<std::string> out;
  if (const char *env = std::getenv("OVTON_IMGCODECS"))
    out.push_back(env);
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec)
    out.push_back((exe.parent_path() / kPluginFile).string());
#ifdef OVTON_IMGCODECS_INSTALLED
  out.push_back(OVTON_IMGCODECS_INSTALLED);
#endif
#ifdef OVTON_IMGCODECS_PLUGIN
  out.push_back(OVTON_IMGCODECS_PLUGIN);
#endif
  return out;
}

const OvtonImageCodecs *open_plugin() {
  std::string tried;
  for (const std::string &file : plugin_candidates()) {
    if (void *handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL)) {
      using Entry = const OvtonImageCodecs *(*)();
      const auto entry = reinterpret_cast<Entry>(dlsym(handle, kOvtonImageCodecsSymbol));
      const OvtonImageCodecs *table = entry ? entry() : nullptr;
      if (table && table->abi == kOvtonImageCodecsAbi)
        return table;
      tried += "\n  " + file + ": not this build's plugin (rebuild ovton)";
      continue;
    }
    tried += "\n  " + file + ": " + dlerror();
  }
  throw std::runtime_error(std::string("OpenCV's image codecs are needed (an image that is not an 8-bit gray PNG, "
                                       "the simulator's writer or a chart) but the plugin ") +
                           kPluginFile + " could not be loaded; tried:" + tried);
}

const OvtonImageCodecs &codecs() {
  // Opened once, by whichever thread asks first (static initialisation is thread-safe); a failure is thrown to that
  // caller and tried again by the next.
  static const OvtonImageCodecs *table = open_plugin();
  return *table;
}

} // namespace

cv::Mat read_gray_image(const std::string &path) {
  cv::Mat img;
  if (read_png_gray8(path, img))
    return img;
  return codecs().read(path, false);
}

cv::Mat decode_gray_image(const uint8_t *data, size_t size) {
  cv::Mat img;
  if (decode_png_gray8(data, size, img))
    return img;
  return codecs().decode(data, size, false);
}

cv::Mat read_color_image(const std::string &path) {
  return codecs().read(path, true);
}

bool write_image(const std::string &path, const cv::Mat &img, const std::vector<int> &params) {
  return codecs().write(path, img, params);
}

bool encode_image(const std::string &ext, const cv::Mat &img, std::vector<uchar> &bytes,
                  const std::vector<int> &params) {
  return codecs().encode(ext, img, params, bytes);
}

int png_compression_param() {
  return codecs().png_compression;
}

int jpeg_quality_param() {
  return codecs().jpeg_quality;
}

} // namespace ovton::core
