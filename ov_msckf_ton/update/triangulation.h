#pragma once
// Triangulation of one feature from its undistorted normalised observations in known camera poses: a linear
// least-squares ray intersection for the initial guess, then Gauss-Newton (Levenberg-Marquardt damped) on the
// inverse-depth parameters (α, β, ρ) of the point in an anchor camera.
#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

namespace ovton::msckf {

/// A camera pose in the world: p_W = R_WC p_C + p_WC.
struct CameraPose {
  Eigen::Matrix3d R_WC = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_WC = Eigen::Vector3d::Zero();
};

struct TriangulationOptions {
  double min_depth = 0.1;        ///< [m] in every observing camera
  double max_depth = 60.0;       ///< [m] in every observing camera
  double min_parallax_deg = 0.2; ///< largest angle between rotation-compensated bearings; below it depth is noise
  double max_condition = 1e5;    ///< condition number of the linear system; above it the rays are near parallel
  double max_reproj_rms = 10.0 / 458.0; ///< RMS reprojection error in normalised units (the updater sets it from px)
  int max_iterations = 20;
  double step_tolerance = 1e-9; ///< convergence on |Δ(α, β, ρ)|
};

enum class TriangulationQuality {
  Ok,
  TooFewObservations,
  LowParallax,
  IllConditioned,
  BadDepth,
  NotConverged,
  LargeReprojection,
};

std::string to_string(TriangulationQuality q);

struct TriangulationResult {
  TriangulationQuality quality = TriangulationQuality::TooFewObservations;
  Eigen::Vector3d p_W = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  double reproj_rms = 0.0;   ///< normalised units, after refinement
  double parallax_rad = 0.0; ///< largest bearing angle against the anchor's
  int iterations = 0;
  bool ok() const { return quality == TriangulationQuality::Ok; }
};

/// Triangulates the point seen at undistorted normalised coordinates xy[i] by camera poses[i]; the anchor is
/// poses[anchor] (the refinement is parameterised in its frame). p_W is filled whenever a point was computed, also
/// when a later check rejects it, so that callers can log what went wrong.
TriangulationResult triangulate(const std::vector<CameraPose> &poses, const std::vector<Eigen::Vector2d> &xy,
                                size_t anchor, const TriangulationOptions &opt);

} // namespace ovton::msckf
