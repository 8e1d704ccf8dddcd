#include "tools/mem_usage.h"

#include <cmath>
#include <cstdio>
#include <sys/resource.h>
#include <unistd.h>

namespace ovton::cli {

double current_rss_mb() {
  std::FILE *f = std::fopen("/proc/self/statm", "r");
  if (!f)
    return std::nan("");
  long size_pages = 0, resident_pages = 0;
  const int n = std::fscanf(f, "%ld %ld", &size_pages, &resident_pages);
  std::fclose(f);
  if (n != 2)
    return std::nan("");
  return static_cast<double>(resident_pages) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

double peak_rss_mb() {
  rusage ru{};
  if (getrusage(RUSAGE_SELF, &ru) != 0)
    return std::nan("");
  return static_cast<double>(ru.ru_maxrss) / 1024.0; // Linux reports kilobytes
}

double process_cpu_s() {
  rusage ru{};
  if (getrusage(RUSAGE_SELF, &ru) != 0)
    return std::nan("");
  const auto s = [](const timeval &t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return s(ru.ru_utime) + s(ru.ru_stime);
}

bool reset_peak_rss() {
  std::FILE *f = std::fopen("/proc/self/clear_refs", "w");
  if (!f)
    return false;
  const bool ok = std::fputs("5", f) >= 0;
  return std::fclose(f) == 0 && ok;
}

} // namespace ovton::cli
