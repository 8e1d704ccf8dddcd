#pragma once
// Per-observation residuals of every feature an MSCKF update examined, with the quantities that could explain them
// (image velocity, image position, depth, body rate, time offset). The `diagnose` tool fits candidate effects
// (time-offset error, rolling shutter, focal/distortion error, IMU scale) against these columns. The row and its
// columns are the schema both the writer and the reader see (ov_core/io/residual_log_schema.h).
#include "ov_core/io/residual_log_schema.h"
#include "ov_msckf_ton/state/state.h"

#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace ovton::msckf {

using ResidualStatus = ovton::core::ResidualStatus;
/// One observation of one feature in one update (ovton::core::ResidualLogRow; `line` stays 0 when written).
using ResidualRecord = ovton::core::ResidualLogRow;

/// The filter's calibration and IMU biases as a calibration-log row (ovton::core::CalibrationLogRow), for the update
/// whose residual rows are `records` (update id and newest camera time from them).
ovton::core::CalibrationLogRow calibration_row(const State &state, const std::vector<ResidualRecord> &records);

/// Writes ResidualRecords as CSV: one header line, then one line per record; and beside it the calibration log
/// (ovton::core::calibration_log_path), one row per update with records. A rig's further cameras' records go to files
/// of their own (ovton::core::residual_log_path_of_camera: res_cam1.csv, ...; opened at their first record), so that
/// `diagnose` reads one camera's tracks at a time. Each batch is flushed so that an interrupted run leaves every
/// finished update on disk.
class ResidualLogWriter {
public:
  /// Opens (truncates) both files and writes their headers; throws ovton::core::DataError when they cannot be written.
  explicit ResidualLogWriter(const std::string &path);
  /// The records of one update and the state after it (its calibration goes to the calibration log).
  void write(const std::vector<ResidualRecord> &records, const State &state);
  /// Records only (no calibration row).
  void write(const std::vector<ResidualRecord> &records);
  const std::string &path() const { return path_; }
  /// Rows written, every camera's.
  size_t rows_written() const { return rows_; }
  /// The further cameras' files written so far.
  std::vector<std::string> camera_paths() const;

  /// The header line (without newline): ovton::core::residual_log_header().
  static std::string header() { return ovton::core::residual_log_header(); }
  /// One record as a CSV line (without newline): ovton::core::format_residual_row().
  static std::string format(const ResidualRecord &r) { return ovton::core::format_residual_row(r); }

private:
  std::ofstream &stream_of_camera(int cam);

  std::string path_, calib_path_;
  std::ofstream out_, calib_out_;
  std::vector<std::unique_ptr<std::ofstream>> more_out_; ///< by cam − 1; null until the camera's first record
  size_t rows_ = 0;
};

} // namespace ovton::msckf
