#include "tools/progress.h"

#include <atomic>
#include <csignal>
#include <cstdio>

namespace ovton::cli {

namespace {
std::atomic<bool> g_interrupted{false};
void on_sigint(int) {
  g_interrupted = true;
}
} // namespace

void install_interrupt_handler() {
  // SIGTERM (a job scheduler, `kill`) stops a run as Ctrl-C does: the rows so far stay, the summary is printed.
  std::signal(SIGINT, on_sigint);
  std::signal(SIGTERM, on_sigint);
}
bool interrupted() {
  return g_interrupted;
}

void ProgressBar::update(size_t done, size_t total, const std::string &extra) {
  if (quiet_ || total == 0)
    return;
  const auto now = std::chrono::steady_clock::now();
  if (done < total && drawn_ && now - last_ < std::chrono::milliseconds(100))
    return;
  last_ = now;
  drawn_ = true;
  const double frac = static_cast<double>(done) / static_cast<double>(total);
  const int width = 30, filled = static_cast<int>(frac * width);
  const double el = std::chrono::duration<double>(now - start_).count();
  const double eta = frac > 0 ? el * (1 - frac) / frac : 0;
  std::fprintf(stderr, "\r%s [%.*s%*s] %5.1f%% %zu/%zu  %.0fs left  %s   ", label_.c_str(), filled,
               "##############################", width - filled, "", 100 * frac, done, total, eta, extra.c_str());
  std::fflush(stderr);
}

void ProgressBar::say(const std::string &line) {
  if (!quiet_ && drawn_)
    std::fprintf(stderr, "\r\033[K");
  std::fprintf(stderr, "%s\n", line.c_str());
  drawn_ = false; // the next update draws the bar again
}

void ProgressBar::finish() {
  if (!quiet_ && drawn_)
    std::fprintf(stderr, "\n");
}

} // namespace ovton::cli
