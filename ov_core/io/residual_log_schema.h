#pragma once
// The residual log's schema, written once: the row, its columns (in file order), writing a row and reading a file.
// `ovton run --residual-log` writes it (ov_msckf_ton/update/residual_log.h) and `ovton diagnose` reads it
// (ov_eval/diagnose.h); it lives in ov_core because both may see ov_core and nothing else, so that the writer and the
// reader cannot drift apart. Adding a column: a field in ResidualLogRow and one line in the table of the .cpp.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace ov_core {

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

/// Reads a residual log. Columns are found by header name, so a reader of this version reads the logs of earlier
/// ones as long as they have the columns it requires (every column but depth_m, td_column, td_ref_s, chi2,
/// chi2_threshold and accepted; a missing one keeps its default) and ignores columns it does not know.
/// Throws DataError with file:line for a missing file, a missing header or required column, a short row, a value
/// that is not a number, a status that is not 0-2, or a NaN where the column (or, for the residual, the row's
/// status) says a number must be.
ResidualLog load_residual_log(const std::string &file);

} // namespace ov_core
