#pragma once
// Shared by the libFuzzer targets: the readers take file paths, so each input is written to files in a private
// temporary folder first; expected rejections (DataError, UsageError) are fine, anything else escaping is a finding.
#include "ov_core/types/errors.h"

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace ovfuzz {

/// A folder unique to this process (libFuzzer's -jobs/-workers run several), created once and removed at exit.
inline const std::filesystem::path &scratch() {
  struct Dir {
    std::filesystem::path path = std::filesystem::temp_directory_path() / ("ovton_fuzz_" + std::to_string(::getpid()));
    Dir() { std::filesystem::create_directories(path); }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Dir dir;
  return dir.path;
}

inline std::string write_file(const std::string &rel, const std::string &bytes) {
  const auto path = scratch() / rel;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path.string();
}

/// The input cut at each "\n%%\n": one fuzz input carries several files (seeds in fuzz/corpus/ show the layout).
inline std::vector<std::string> split_parts(const uint8_t *data, size_t size, size_t max_parts) {
  const std::string in(reinterpret_cast<const char *>(data), size);
  const std::string sep = "\n%%\n";
  std::vector<std::string> parts;
  size_t start = 0;
  while (parts.size() + 1 < max_parts) {
    const size_t pos = in.find(sep, start);
    if (pos == std::string::npos)
      break;
    parts.push_back(in.substr(start, pos - start));
    start = pos + sep.size();
  }
  parts.push_back(in.substr(start));
  return parts;
}

/// Runs f; the library's typed rejections of bad input are the expected outcome.
template <typename F> void expect_clean(F &&f) {
  try {
    f();
  } catch (const ovton::core::DataError &) {
  } catch (const ovton::core::UsageError &) {
  }
}

} // namespace ovfuzz
