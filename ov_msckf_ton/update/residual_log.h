#pragma once
// Per-observation residuals of every feature an MSCKF update examined, with the quantities that could explain them
// (image velocity, image position, depth, body rate, time offset). The `diagnose` tool fits candidate effects
// (time-offset error, rolling shutter, focal/distortion error, IMU scale) against these columns. The row and its
// columns are the schema both the writer and the reader see (ov_core/io/residual_log_schema.h).
#include "ov_core/io/residual_log_schema.h"

#include <fstream>
#include <string>
#include <vector>

namespace ov_msckf_ton {

using ResidualStatus = ov_core::ResidualStatus;
/// One observation of one feature in one update (ov_core::ResidualLogRow; `line` stays 0 when written).
using ResidualRecord = ov_core::ResidualLogRow;

/// Writes ResidualRecords as CSV: one header line, then one line per record. Each batch is flushed so that an
/// interrupted run leaves every finished update on disk.
class ResidualLogWriter {
public:
  /// Opens (truncates) the file and writes the header; throws ov_core::DataError when it cannot be written.
  explicit ResidualLogWriter(const std::string &path);
  void write(const std::vector<ResidualRecord> &records);
  const std::string &path() const { return path_; }
  size_t rows_written() const { return rows_; }

  /// The header line (without newline): ov_core::residual_log_header().
  static std::string header() { return ov_core::residual_log_header(); }
  /// One record as a CSV line (without newline): ov_core::format_residual_row().
  static std::string format(const ResidualRecord &r) { return ov_core::format_residual_row(r); }

private:
  std::string path_;
  std::ofstream out_;
  size_t rows_ = 0;
};

} // namespace ov_msckf_ton
