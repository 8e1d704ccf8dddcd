#pragma once
// Typed errors for library code. The CLI is the only place that turns them into a message and an exit code.
#include <cstdint>
#include <stdexcept>
#include <string>

namespace ovton::core {

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

/// The estimate went wrong although the input was readable: a non-finite state or covariance, an update acceptance
/// that collapsed, innovations far beyond chance. Thrown instead of writing rows that look like an answer; the rows
/// written before it stay on disk. `t_ns` is the IMU-clock time at which it was detected (0 when unknown).
class EstimatorFailure : public std::runtime_error {
public:
  EstimatorFailure(int64_t t_ns, const std::string &what) : std::runtime_error(what), t_ns_(t_ns) {}
  int64_t t_ns() const { return t_ns_; }

private:
  int64_t t_ns_;
};

} // namespace ovton::core
