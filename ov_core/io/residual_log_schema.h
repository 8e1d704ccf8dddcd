#pragma once
// The residual log's schema, written once: the row, its columns (in file order), writing a row and reading a file.
// `ovton run --residual-log` writes it (ov_msckf_ton/update/residual_log.h) and `ovton diagnose` reads it
// (ov_eval/diagnose.h); it lives in ov_core because both may see ov_core and nothing else, so that the writer and the
// reader cannot drift apart. Adding a column: a field in ResidualLogRow and one line in the table of the .cpp.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace ovton::core {

/// Why a feature did or did not enter the update.
enum class ResidualStatus : int {
  Accepted = 0,
  GatedChi2 = 1,           ///< failed the chi-square test after nullspace projection
  TriangulationFailed = 2, ///< residuals use the rejected point when one was computed, NaN otherwise
};

/// One observation of one feature in one update, with the quantities that could explain its residual (image
/// velocity, image position, depth, body rate, time offset). Pixel quantities are the normalised ones scaled by the
/// focal lengths (fu, fv): the distortion's local scale is left out so that residual and velocity share one scale.
struct ResidualLogRow {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  long line = 0; ///< 1-based line in the file it was read from (0 when not read from a file), for messages
  /// The rig's camera that made the observation (0: the primary). Not a column: each camera's rows go to a file of
  /// their own (residual_log_path_of_camera), so that a track's rows in one file are one camera's.
  int cam = 0;
  uint64_t update_id = 0;
  int64_t t_cam_ns = 0;
  uint64_t feature_id = 0;
  int obs_index = 0;                       ///< index in the feature's observation list
  int track_length = 0;                    ///< observations in the feature's track
  double res_u_px = kNaN, res_v_px = kNaN; ///< z − h(x̂, p̂_f) before nullspace projection (image-plane shift applied)
  double u_px = 0.0, v_px = 0.0;           ///< measured distorted pixel (v = image row)
  double x_norm = 0.0, y_norm = 0.0;       ///< measured undistorted normalised coordinates
  double vel_u_px_s = 0.0, vel_v_px_s = 0.0; ///< image velocity from the VelocityProvider, 0 when none
  int vel_source = 0;                        ///< VelocitySource: 0 none, 1 tracked, 2 ITS-FVON, 3 F2F-FVON
  int td_column = 0;                         ///< 1 when the row carried a t_d entry (image-plane mode)
  double depth_m = kNaN;                     ///< z of the triangulated point in this camera; NaN if unknown
  double radius_norm = 0.0;                  ///< |xy| undistorted: distortion errors grow with it
  double w_x = 0.0, w_y = 0.0, w_z = 0.0;    ///< body angular rate at the clone [rad/s], when known
  int w_valid = 0;
  double td_s = 0.0;     ///< t̂_d when the update started
  double td_ref_s = 0.0; ///< t̂_d the clone was placed with
  double chi2 = kNaN, chi2_threshold = kNaN;
  int accepted = 0;
  ResidualStatus status = ResidualStatus::Accepted;
};

struct ResidualLog {
  std::string file;
  std::vector<ResidualLogRow> rows;
};

/// The header line (without newline): the column names in file order.
std::string residual_log_header();
/// One row as a CSV line (without newline): integers exactly, reals with 10 significant digits, NaN as "nan".
std::string format_residual_row(const ResidualLogRow &r);

/// Where camera `cam`'s rows of the residual log `path` go: `path` itself for the primary camera (0), else the path
/// with "_cam<cam>" before its extension (res.csv -> res_cam1.csv).
std::string residual_log_path_of_camera(const std::string &path, int cam);
/// The camera a residual log's file name says it holds: K for a name ending in "_camK" before the extension, else 0.
int camera_of_residual_log(const std::string &path);

/// Reads a residual log. Columns are found by header name, so a reader of this version reads the logs of earlier
/// ones as long as they have the columns it requires (every column but depth_m, td_column, td_ref_s, chi2,
/// chi2_threshold and accepted; a missing one keeps its default) and ignores columns it does not know.
/// Throws DataError with file:line for a missing file, a missing header or required column, a short row, a value
/// that is not a number, a status that is not 0-2, or a NaN where the column (or, for the residual, the row's
/// status) says a number must be.
ResidualLog load_residual_log(const std::string &file);

/// The filter's calibration and IMU biases after one update: the companion of a residual log (`ovton run
/// --residual-log res.csv` writes it to calibration_log_path("res.csv") = "res_calib.csv", one row per update that
/// logged residuals). `diagnose` compares the images and the raw IMU through these values (the calibration the filter
/// held at each image), so that an effect the filter has estimated is no longer named. Fixed values when a block is
/// not estimated (`estimated` says which are). Conventions as in the state (ov_msckf_ton/state/state.h):
/// R_BC camera -> body, row-major; intrinsics fu fv cu cv d0..d3; a row v is seen at t + t_d + (v/H − ½)·readout_s;
/// ω = D_w·(ω_m − b_g), a = D_a·(a_m − b_a) (D_w, D_a row-major). The IMU state after the update (its time, q_WB and
/// v_W) follows: with it `diagnose` tests the accelerometer against gravity (docs/diagnose.md, "Accelerometer scale
/// against gravity"). Logs written before those columns existed are still read, without them (has_state false).
struct CalibrationLogRow {
  enum Estimated : int { kExtrinsics = 1, kIntrinsics = 2, kReadout = 4, kImuIntrinsics = 8 };
  long line = 0; ///< 1-based line in the file it was read from
  uint64_t update_id = 0;
  int64_t t_cam_ns = 0; ///< the newest camera time among the update's residual rows
  int estimated = 0;    ///< bitmask of Estimated
  double td_s = 0.0;    ///< t̂_d after the update
  double R_BC[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  double p_BC[3] = {0, 0, 0};
  double intrinsics[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  double readout_s = 0.0;
  double D_w[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  double D_a[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  double b_g[3] = {0, 0, 0};
  double b_a[3] = {0, 0, 0};
  bool has_state = false;        ///< the row carries the IMU state below
  int64_t t_imu_ns = 0;          ///< the time the IMU state refers to (IMU clock)
  double q_WB[4] = {1, 0, 0, 0}; ///< orientation, w x y z (Hamilton, body -> world)
  double v_W[3] = {0, 0, 0};     ///< velocity in the world frame [m/s]
};

/// "dir/res.csv" -> "dir/res_calib.csv" (any extension: "res" -> "res_calib.csv").
std::string calibration_log_path(const std::string &residual_log);
/// The header line (without newline) and one row as a CSV line (reals with 10 significant digits; the IMU state's
/// columns when the row has_state, which every row of one file must agree on).
std::string calibration_log_header(bool with_state = true);
std::string format_calibration_row(const CalibrationLogRow &r);
/// Reads a calibration log (every column required, all finite, rows in update order; the header with or without the
/// IMU state's columns). Throws DataError with file:line like load_residual_log.
std::vector<CalibrationLogRow> load_calibration_log(const std::string &file);

} // namespace ovton::core
