#pragma once
// Typed error for the online networks. Library code never exits; the caller (filter or CLI) decides what to do.
#include <stdexcept>
#include <string>

namespace ovton::msckf {
namespace ton {

/// Misuse of a network or its wrapper (predict before train, non-finite label, malformed sequence). Carries the
/// source location so a failure inside a long replay can be traced without a debugger.
class TonError : public std::runtime_error {
public:
  TonError(const char *file, int line, const std::string &what)
      : std::runtime_error(std::string(file) + ":" + std::to_string(line) + ": " + what), file_(file), line_(line) {}
  const char *file() const { return file_; }
  int line() const { return line_; }

private:
  const char *file_;
  int line_;
};

} // namespace ton
} // namespace ovton::msckf

/// Throws TonError with the caller's location when `cond` is false. Unlike assert() it stays in Release builds.
#define OVTON_TON_CHECK(cond, msg)                                                                                     \
  do {                                                                                                                 \
    if (!(cond))                                                                                                       \
      throw ::ovton::msckf::ton::TonError(__FILE__, __LINE__, (msg));                                                  \
  } while (0)
