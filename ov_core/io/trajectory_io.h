#pragma once
// Trajectory files: the project CSV (columns in docs/architecture.md), TUM text, and EuRoC ground truth.
#include "ov_core/types/sensor_data.h"
#include <fstream>
#include <string>
#include <vector>

namespace ovton::core {

enum class TrajectoryFormat { Csv, Tum };

/// Header of the project trajectory CSV; EuRoC ground-truth column order plus td.
extern const char *const kTrajectoryCsvHeader;

/// Writes one row per call and flushes, so an interrupted run keeps every row it wrote.
class TrajectoryWriter {
public:
  /// `camera_tds`: CSV columns td_camK_s,td_camK_sigma_s for K = 1..camera_tds after the 19 (a rig with an offset
  /// per camera; StateSample::cam_td_s, NaN where a row has none). Appended, so readers of the 19 keep working.
  TrajectoryWriter(const std::string &file, TrajectoryFormat fmt = TrajectoryFormat::Csv, int camera_tds = 0);
  void write(const StateSample &s);
  const std::string &file() const { return file_; }

private:
  std::string file_;
  TrajectoryFormat fmt_;
  int camera_tds_ = 0;
  std::ofstream out_;
};

/// Reads any trajectory this project meets, by content:
///  - project CSV / EuRoC state_groundtruth_estimate0/data.csv (17 columns, 19 with td, 19 + 2K with K further
///    cameras' offsets) with either header;
///  - text `# timestamp(s) tx ty tz qx qy qz qw` (TUM / ../shared/data/euroc_groundtruth/*.txt);
///  - position-only CSV `timestamp_ns,px,py,pz` (SCube RTK).
/// Rows must be strictly increasing in time; NaN, wrong column counts and bad numbers throw DataError with the line.
std::vector<StateSample> read_trajectory(const std::string &file);

/// EuRoC state_groundtruth_estimate0/data.csv (17 columns, original EuRoC header), written in one go.
void write_euroc_groundtruth(const std::string &file, const std::vector<StateSample> &gt);

/// td_truth/data.csv: `timestamp_ns,td_s` (camera-clock stamp of each image and its true offset).
std::vector<TdSample> read_td_truth(const std::string &file);
void write_td_truth(const std::string &file, const std::vector<TdSample> &td);

} // namespace ovton::core
