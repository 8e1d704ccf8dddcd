#pragma once
// The first stages of `ovton diagnose`: which rows of the log it uses, grouped into tracks, and the camera's
// intrinsics and image height (docs/diagnose.md, "Data used").
#include "ov_eval/diagnose.h"

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace ovton::eval::diag {

/// Observations (rows in tracks of 3+) below which a log is not diagnosed.
constexpr long kMinObservations = 50;

/// One feature in one update, its rows in time order.
using Track = std::vector<const ResidualLogRow *>;
using TrackMap = std::map<std::pair<uint64_t, uint64_t>, Track>; ///< keyed by (update_id, feature_id)

struct UsedData {
  std::vector<const ResidualLogRow *> rows; ///< accepted or gated (and, with the logged velocity, with one)
  TrackMap tracks;                          ///< tracks of 3+ of those rows
  long observations = 0;                    ///< rows in the tracks
  bool use_velocity = false;                ///< the time candidates can be tested (an image velocity per row)
  int64_t t_first = 0, t_last = 0;          ///< first and last camera time in the tracks [ns]
};

/// Rows with a residual (status 0 or 1) in tracks of 3+; fills rep's row counts, tracks_used and duration_s.
/// Below kMinObservations of them nothing is testable (diagnose() says so).
UsedData select_data(const ResidualLog &log, const DiagnoseOptions &opt, DiagnoseReport &rep);

/// The intrinsics (the dataset's camera, given, or fitted from the log's u ≈ cu + fu·x) and the image height, into
/// rep. Throws DataError when they cannot be fitted.
void set_intrinsics(const UsedData &data, const DiagnoseOptions &opt, const std::string &log_file, DiagnoseReport &rep);

} // namespace ovton::eval::diag
