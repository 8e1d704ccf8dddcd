#pragma once
// Per-observation residuals of every feature an MSCKF update examined, with the quantities that could explain them
// (image velocity, image position, depth, body rate, time offset). The `diagnose` tool fits candidate effects
// (time-offset error, rolling shutter, focal/distortion error, IMU scale) against these columns.
#include <Eigen/Core>
#include <cstdint>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace ov_msckf_ton {

/// Why a feature did or did not enter the update.
enum class ResidualStatus : int {
  Accepted = 0,
  GatedChi2 = 1,           ///< failed the chi-square test after nullspace projection
  TriangulationFailed = 2, ///< residuals use the rejected point when one was computed, NaN otherwise
};

/// One observation of one feature in one update. Pixel quantities are the normalised ones scaled by the focal
/// lengths (fu, fv): the distortion's local scale is left out so that residual and velocity share one scale.
struct ResidualRecord {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
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
  double depth_m = kNaN;                     ///< z of the triangulated point in this camera
  double radius_norm = 0.0;                  ///< |xy| undistorted: distortion errors grow with it
  double w_x = 0.0, w_y = 0.0, w_z = 0.0;    ///< body angular rate at the clone [rad/s], when known
  int w_valid = 0;
  double td_s = 0.0;     ///< t̂_d when the update started
  double td_ref_s = 0.0; ///< t̂_d the clone was placed with
  double chi2 = kNaN, chi2_threshold = kNaN;
  int accepted = 0;
  ResidualStatus status = ResidualStatus::Accepted;
};

/// Writes ResidualRecords as CSV: one header line, then one line per record. Each batch is flushed so that an
/// interrupted run leaves every finished update on disk.
class ResidualLogWriter {
public:
  /// Opens (truncates) the file and writes the header; throws ov_core::DataError when it cannot be written.
  explicit ResidualLogWriter(const std::string &path);
  void write(const std::vector<ResidualRecord> &records);
  const std::string &path() const { return path_; }
  size_t rows_written() const { return rows_; }

  /// The header line (without newline); the column list lives in one table in the .cpp so adding a column is
  /// one line there.
  static std::string header();
  /// One record as a CSV line (without newline).
  static std::string format(const ResidualRecord &r);

private:
  std::string path_;
  std::ofstream out_;
  size_t rows_ = 0;
};

} // namespace ov_msckf_ton
