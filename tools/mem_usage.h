#pragma once
// Resident memory and CPU time of this process, for the benchmark's "does memory stay flat" and cost columns. Linux
// only; elsewhere the memory functions return NaN and the benchmark prints "n/a".

namespace ovton::cli {

/// Current resident set size [MB] from /proc/self/statm (cheap: one small read, fine to call every frame).
double current_rss_mb();

/// Peak resident set size [MB] of the process so far, from getrusage (ru_maxrss).
double peak_rss_mb();

/// Resets the kernel's peak-RSS mark to the current RSS (writes "5" to /proc/self/clear_refs, Linux >= 4.0), so the
/// next mode's peak is its own and not the earlier modes'. Returns false when the kernel refuses; the peak is then
/// process-wide.
bool reset_peak_rss();

/// CPU time (user + system, all threads) of this process so far [s], from getrusage.
double process_cpu_s();

} // namespace ovton::cli
