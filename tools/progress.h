#pragma once
// A one-line progress bar on stderr and SIGINT/SIGTERM handling for long runs (an interrupted run stops cleanly and
// keeps the rows it has written).
#include <chrono>
#include <string>

namespace ovton::cli {

void install_interrupt_handler();
bool interrupted();

class ProgressBar {
public:
  ProgressBar(std::string label, bool quiet) : label_(std::move(label)), quiet_(quiet) {}
  /// Redraws at most ~10 times a second.
  void update(size_t done, size_t total, const std::string &extra = "");
  /// A line of its own above the bar (printed even when quiet: the caller decides whether to say it).
  void say(const std::string &line);
  void finish();

private:
  std::string label_;
  bool quiet_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_{};
};

} // namespace ovton::cli
