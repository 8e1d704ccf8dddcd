#pragma once
// Typed errors for library code. The CLI is the only place that turns them into a message and an exit code.
#include <stdexcept>
#include <string>

namespace ov_core {

/// Bad or missing input data. Carries the file and (1-based) line so the user can find the problem.
class DataError : public std::runtime_error {
public:
  DataError(const std::string &file, long line, const std::string &what)
      : std::runtime_error(format(file, line, what)), file_(file), line_(line) {}
  DataError(const std::string &file, const std::string &what) : DataError(file, 0, what) {}

  const std::string &file() const { return file_; }
  /// 1-based line number, 0 when the error concerns the whole file.
  long line() const { return line_; }

private:
  static std::string format(const std::string &file, long line, const std::string &what) {
    return line > 0 ? file + ":" + std::to_string(line) + ": " + what : file + ": " + what;
  }
  std::string file_;
  long line_;
};

/// A request that cannot be satisfied (bad option value, inconsistent inputs).
class UsageError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

} // namespace ov_core
