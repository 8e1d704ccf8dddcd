#pragma once
// The velocity log: per observation of every feature an update uses, the image-plane velocity each rule or network
// gives it (paper eq. 2, `next`, ITS-FVON, F2F-FVON). Written by the estimator (`ovton run --velocity-log`), read by
// `ovton velocities`, which scores each against the true velocity. One schema, here, for both sides.
#include <cstdint>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace ovton::core {

/// One observation. Velocities are in undistorted pixels per second (normalised coordinates × the mean focal
/// length, the unit FVON and its gate work in); NaN where the rule or network gave none.
struct VelocityLogRow {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  int64_t t_cam_ns = 0;
  uint64_t feature_id = 0;
  int obs_index = 0;                   ///< index in the feature's observation list at the update
  int track_length = 0;                ///< observations in the feature's list at the update
  double u_px = 0, v_px = 0;           ///< distorted pixel
  double x_norm = 0, y_norm = 0;       ///< undistorted normalised
  double eq2_x = kNaN, eq2_y = kNaN;   ///< backward difference with the previous observation (paper eq. 2)
  double next_x = kNaN, next_y = kNaN; ///< the next observation's eq. 2 velocity (rule `next`)
  double its_x = kNaN, its_y = kNaN;   ///< ITS-FVON's prediction (first observations)
  double f2f_x = kNaN, f2f_y = kNaN;   ///< F2F-FVON's prediction (first observations)
  int used_source = 0;                 ///< velocity source the update used (0 none, 1 tracked, 2 ITS, 3 F2F)
  int fvon_source = 0; ///< the network Algorithm 1 picked for this first observation (2 ITS, 3 F2F, 0 none)
  int gated = 0;       ///< FVON's prediction for this observation failed the sanity gate
  double focal_px = 0; ///< the mean focal length the pixel velocities were scaled by
};

/// CSV with one header line; each batch is flushed so an interrupted run keeps what was written.
class VelocityLogWriter {
public:
  explicit VelocityLogWriter(const std::string &path); ///< throws DataError when the file cannot be written
  void write(const std::vector<VelocityLogRow> &rows);
  static std::string header();

private:
  std::string path_;
  std::ofstream out_;
};

/// Reads a velocity log; errors name the file and line.
std::vector<VelocityLogRow> read_velocity_log(const std::string &path);

} // namespace ovton::core
