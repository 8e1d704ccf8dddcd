#pragma once
// Shared helpers for the test suite: temporary folders, the path of ../shared/data, small file writers.
#include "ov_core/types/errors.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace ovtest {

/// ../shared/data beside the checkout (present on developer machines and CI, absent in a user's clone).
inline std::string shared_data() {
  return std::string(OVTON_SOURCE_DIR) + "/../shared/data";
}
inline bool have_shared_data() {
  return std::filesystem::is_directory(shared_data() + "/euroc_groundtruth");
}

#define OVTEST_REQUIRE_SHARED_DATA()                                                                                   \
  do {                                                                                                                 \
    if (!ovtest::have_shared_data())                                                                                   \
      GTEST_SKIP() << "../shared/data not found beside the checkout (" << ovtest::shared_data()                        \
                   << "): this test needs the real EuRoC reference data";                                              \
  } while (0)

/// A fresh folder under the system temp dir, removed when the object goes out of scope.
class TempDir {
public:
  TempDir() {
    std::random_device rd;
    path_ = std::filesystem::temp_directory_path() / ("ovton_test_" + std::to_string(rd()) + std::to_string(rd()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string str() const { return path_.string(); }
  std::string operator/(const std::string &rel) const { return (path_ / rel).string(); }

private:
  std::filesystem::path path_;
};

inline void write_text(const std::string &file, const std::string &text) {
  std::filesystem::create_directories(std::filesystem::path(file).parent_path());
  std::ofstream out(file);
  out << text;
}

inline std::string read_text(const std::string &file) {
  std::ifstream in(file);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// Runs f and checks it throws DataError whose message names `file_part` and, if line > 0, that line.
template <typename F>
inline void expect_data_error(F f, const std::string &file_part, long line, const std::string &why) {
  try {
    f();
    ADD_FAILURE() << "expected a DataError for " << why;
  } catch (const ovton::core::DataError &e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(file_part), std::string::npos) << why << ": message does not name the file: " << msg;
    if (line > 0) {
      EXPECT_EQ(e.line(), line) << why << ": " << msg;
      EXPECT_NE(msg.find(":" + std::to_string(line) + ":"), std::string::npos) << msg;
    }
  } catch (const std::exception &e) {
    ADD_FAILURE() << why << ": wrong exception type: " << e.what();
  }
}

} // namespace ovtest
