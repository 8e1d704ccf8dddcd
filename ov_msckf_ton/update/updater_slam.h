#pragma once
// SLAM features (as OpenVINS): long-lived landmarks kept in the state next to the MSCKF window. A feature tracked
// through the whole window is, instead of being used once by the MSCKF and forgotten, initialised into the state by
// delayed initialisation (its window observations fix it; the rest of their information updates the state), then
// updated by every new observation, and marginalised when the tracker loses it. Its information then carries past
// the window's 1 s instead of being cut at the window's edge.
#include "ov_core/cam/camera_calib.h"
#include "ov_core/track/feature_database.h"
#include "ov_msckf_ton/state/state.h"
#include "ov_msckf_ton/update/td_observation.h"
#include "ov_msckf_ton/update/updater_msckf.h"

#include <Eigen/Core>
#include <vector>

namespace ovton::msckf {

struct SlamStats {
  int initialised = 0, init_rejected = 0; ///< delayed initialisations done / refused (triangulation or chi2)
  int updated = 0, gated = 0;             ///< landmark observations used / refused by the chi2 gate this frame
  int marginalised = 0;
};

/// The measurement of one landmark in one clone: residual r = Jd (z − V·(t_d − td_ref) − π(clone, p_f)) in pixels
/// (the V term in image-plane modes only), Jacobians w.r.t. the clone's [δθ δp] (at its first estimate), the
/// landmark's δp_f (at its first estimate) and t_d (+Jd·V, as UpdaterMSCKF::linearize).
struct LandmarkLinearization {
  Eigen::Vector2d r = Eigen::Vector2d::Zero();
  Eigen::Matrix<double, 2, 6> H_clone = Eigen::Matrix<double, 2, 6>::Zero();
  Eigen::Matrix<double, 2, 3> H_f = Eigen::Matrix<double, 2, 3>::Zero();
  Eigen::Vector2d H_td = Eigen::Vector2d::Zero();
  bool td_column = false;
  /// A further camera with its own offset Δ_k (time_offset.per_camera): the column +Jd·V of δΔ_k, state index
  /// delta_index (−1: no such column).
  Eigen::Vector2d H_delta = Eigen::Vector2d::Zero();
  int delta_index = -1;
  std::vector<int> calib_cols;                      ///< state indices of H_calib's columns
  Eigen::Matrix<double, 2, Eigen::Dynamic> H_calib; ///< extrinsics, intrinsics, readout where estimated
  double depth = 0.0;
};

class UpdaterSLAM {
public:
  /// `msckf` supplies the shared triangulation, linearisation, distortion Jacobian and chi-square table.
  UpdaterSLAM(const ovton::core::CameraCalib &calib, const UpdaterSlamOptions &opt, const UpdaterMSCKF &msckf);

  /// Delayed initialisation (OpenVINS' StateHelper::initialize): each feature is triangulated and linearised over
  /// its window observations as for an MSCKF update, r = H_x δx + H_f δp_f + n; the QR of H_f splits the rows
  ///   top 3:       r₁ = H_x1 δx + R₁ δp_f + n₁   -> the landmark: p_f += R₁⁻¹ r₁,
  ///                P_ff = R₁⁻¹ (H_x1 P H_x1ᵀ + σ²I) R₁⁻ᵀ,  P_xf = −P H_x1ᵀ R₁⁻ᵀ;
  ///   remaining:   r₂ = H_x2 δx + n₂              -> an EKF update of the state (and, through P_xf, the landmark),
  /// after a chi-square test of r₂. Features that fail either step stay out of the state.
  void initialize(State &state, const std::vector<const ovton::core::Feature *> &features, int64_t t_cam_ns,
                  TdObservation td_obs, const VelocityProvider &velocities, SlamStats &stats);

  /// Updates every landmark observed at t_cam_ns (the newest clone) with that observation in the primary camera and,
  /// with UpdaterSlamOptions::further_cameras, in each further camera of the rig:
  /// one chi-square test per observation (2 dof), the passing ones stacked into one EKF update. A further camera's
  /// observation follows the MSCKF's rule (UpdaterMSCKF::usable_observations): in image-plane modes, or with an offset
  /// of its own, it needs its eq. 2 velocity, else it is left out. Landmarks that can no longer be linearised
  /// (behind the camera, outside the depth range) are appended to `drop` for the caller to marginalise. `motion`:
  /// the body's motion at t_cam_ns, for the predicted velocities of image-plane modes (state_velocity).
  void update(State &state, const ovton::core::FeatureDatabase &db, int64_t t_cam_ns, TdObservation td_obs,
              const VelocityProvider &velocities, SlamStats &stats, std::vector<size_t> &drop,
              const BodyMotion *motion = nullptr);

  /// A new landmark's covariance blocks in covariance C (the state before it), from the top three rows of its window
  /// (H1 over `cols`, R1inv, N1 their noise covariance): its error −R₁⁻¹(H₁δx + n₁) has cross-covariance
  /// P_xf = −C H₁ᵀR₁⁻ᵀ and covariance P_ff = R₁⁻¹(H₁CH₁ᵀ + N₁)R₁⁻ᵀ.
  struct LandmarkBlock {
    Eigen::MatrixXd P_xf;
    Eigen::Matrix3d P_ff = Eigen::Matrix3d::Zero();
  };
  /// (C: the filter's P or the reported P_report; computed in double either way.)
  template <class Mat>
  static LandmarkBlock landmark_block(const Mat &C, const std::vector<int> &cols, const Eigen::MatrixXd &H1,
                                      const Eigen::Matrix3d &R1inv, const Eigen::Matrix3d &N1);
  /// Writes it into C once the landmark is the variable at `index`.
  template <class Mat> static void write_landmark_block(Mat &C, int index, const LandmarkBlock &b);

  /// With a separately reported covariance (State::P_report): the new landmark's reported blocks from the window's
  /// rows (H1 its top three, R1inv, qr of H_f) under the track model, and in dR2 the extra noise ΔR₂ of the remaining
  /// rows (for their update, ekf_update's ReportNoise::rows).
  LandmarkBlock report_initialization(const State &state, const std::vector<int> &cols, const Eigen::MatrixXd &H1,
                                      const Eigen::Matrix3d &R1inv, const UpdaterMSCKF::FeatureQR &qr, double sigma2,
                                      Eigen::MatrixXd &dR2) const;

  /// Residual and Jacobians of landmark `l` seen at observation `obs_index` of `feature` in `clone`; false when
  /// the landmark is behind the camera or outside the depth range.
  bool linearize(const State &state, const LandmarkState &l, const CloneState &clone,
                 const ovton::core::Feature &feature, size_t obs_index, TdObservation td_obs,
                 const VelocityProvider &velocities, LandmarkLinearization &out) const {
    return linearize(msckf_.camera_view(state), state, l, clone, feature, obs_index, td_obs, velocities, out);
  }
  /// The same with the calibration view of the update (UpdaterMSCKF::camera_view), computed once per update. The
  /// calibration columns (extrinsics, intrinsics, readout: those the state estimates) are H_calib, in the order of
  /// `calib_cols`. `motion` (the body's at the clone): in image-plane modes with state_velocity the observation's
  /// velocity is the one the landmark's state predicts, not the provider's.
  bool linearize(const UpdaterMSCKF::CameraView &view, const State &state, const LandmarkState &l,
                 const CloneState &clone, const ovton::core::Feature &feature, size_t obs_index, TdObservation td_obs,
                 const VelocityProvider &velocities, LandmarkLinearization &out,
                 const BodyMotion *motion = nullptr) const;

private:
  /// With correlated track errors: linearises the landmark's previous observation of `f` (in `prev`) and turns `lin`
  /// into the differenced measurement (lin − ρ·prev)/√(1 − ρ²), prev.H_clone into the block of the previous clone
  /// (its state index in prev_clone_index).
  /// False (lin untouched) when that observation's clone has left the state or its columns differ from lin's.
  bool difference_previous(const UpdaterMSCKF::CameraView &view, const State &state, const LandmarkState &l,
                           const ovton::core::Feature &f, TdObservation td_obs, const VelocityProvider &velocities,
                           LandmarkLinearization &lin, LandmarkLinearization &prev, int &prev_clone_index) const;

  UpdaterSlamOptions opt_;
  const UpdaterMSCKF &msckf_;
  double sigma_px_; ///< opt_.sigma_px, or the MSCKF updater's when that is 0
  FeatureLinearization lin_;
};

} // namespace ovton::msckf
