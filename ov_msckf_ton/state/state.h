#pragma once
// The filter state: IMU navigation state, the time offset t_d, and a window of cloned poses, with one dense
// covariance whose blocks the variables index.
//
// Error-state convention (the only place it is written; every Jacobian test checks it numerically):
//   R_WB = Exp(δθ) · R̂_WB          rotation: left (world-frame) perturbation, Hamilton, body -> world
//   p = p̂ + δp,  v = v̂ + δv        world-frame position and velocity of the IMU/body
//   b_g = b̂_g + δb_g,  b_a = b̂_a + δb_a
//   t_d = t̂_d + δt_d               t_imu = t_cam + t_d
//   ṫ_d = ṫ̂_d + δṫ_d               rate of t_d [s/s], only with the drift-state model (td/td_drift.cpp)
//   Δ_k = Δ̂_k + δΔ_k               camera k ≥ 1's own offset, only with time_offset.per_camera: its images are at
//                                  t_imu = t_cam + t_d + Δ_k (t_d is cam0's; CameraTdState says why a difference)
//   Δ̇_k = Δ̇̂_k + δΔ̇_k               its rate [s/s], only with time_offset.per_camera_rate as well
// Online calibration (each only when estimated, calibration.* options):
//   R_BC = Exp(δθ_BC) · R̂_BC       camera–IMU rotation, error on the body side; p_BC = p̂_BC + δp_BC
//   k = k̂ + δk                     intrinsics [fu fv cu cv d0 d1 d2 d3] (radtan k1 k2 p1 p2 / equidistant k1..k4)
//   t_r = t̂_r + δt_r               rolling-shutter readout: row v is seen at t + t_d + (v/H − ½)·t_r
//   D_w = D̂_w + δD_w, D_a = D̂_a + δD_a   IMU scale/misalignment, lower triangles (6 + 6): ω = D_w (ω_m − b_g),
//                                        a = D_a (a_m − b_a)
// Clones use the same rotation and position convention.
//
// Why world-frame: the directions the filter cannot observe (yaw about gravity, global position) are then fixed
// vectors in error coordinates, and first-estimate Jacobians (FEJ: propagation and measurement Jacobians evaluated
// at the first estimate of each variable, Huang et al. / Li & Mourikis) keep them unobservable. Without FEJ the
// filter gains spurious information along them and becomes over-confident (NEES well above 3).
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <type_traits>
#include <vector>

namespace ovton::msckf {

/// IMU state; the error block [δθ δp δv δb_g δb_a] sits at covariance index `index` (always 0).
struct ImuState {
  static constexpr int kSize = 15;
  static constexpr int kTheta = 0, kPos = 3, kVel = 6, kBg = 9, kBa = 12;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();
  int index = 0;
  /// First estimates for FEJ: the values of the last propagation before any update touched them.
  Eigen::Matrix3d R_fej = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_fej = Eigen::Vector3d::Zero(), v_fej = Eigen::Vector3d::Zero();
  void set_fej() {
    R_fej = R;
    p_fej = p;
    v_fej = v;
  }
};

/// The body's motion at an image: the bias-corrected rate and the world-frame velocity the filter had there. Not
/// state variables: constants of the linearisation (t_d's state-relevant Jacobian, predicted image velocities).
struct BodyMotion {
  Eigen::Vector3d w_B = Eigen::Vector3d::Zero(); ///< body rate, bias-corrected [rad/s]
  Eigen::Vector3d v_W = Eigen::Vector3d::Zero(); ///< velocity in the world frame [m/s]
};

/// A cloned IMU pose [δθ δp] at the IMU-clock time of one image; keyed in the window by the image's camera stamp.
struct CloneState {
  static constexpr int kSize = 6;
  int64_t t_cam_ns = 0;
  int64_t t_imu_ns = 0; ///< t_cam + t̂_d at cloning time
  double td_ref = 0.0;  ///< t̂_d used to place the clone (image-plane modes shift observations by V·(t_d − td_ref))
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  int index = -1;
  /// First estimate (the pose when cloned): measurement Jacobians are evaluated here (FEJ); residuals use R, p.
  bool has_fej = false;
  Eigen::Matrix3d R_fej = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_fej = Eigen::Vector3d::Zero();
  /// The motion it was cloned with (state_helper::clone): rows that need the image's motion (the rolling shutter's
  /// row times, the residual log's rate) read it here.
  bool has_motion = false;
  BodyMotion motion;
  const Eigen::Matrix3d &R_lin() const { return has_fej ? R_fej : R; }
  const Eigen::Vector3d &p_lin() const { return has_fej ? p_fej : p; }
};

/// The camera and IMU calibration as the filter holds it: fixed values from the dataset, or state variables when
/// an index is >= 0.
struct CalibState {
  Eigen::Matrix3d R_BC = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_BC = Eigen::Vector3d::Zero();
  int extrinsics_index = -1;                                                    ///< [δθ_BC δp_BC]
  Eigen::Matrix<double, 8, 1> intrinsics = Eigen::Matrix<double, 8, 1>::Zero(); ///< fu fv cu cv d0..d3
  int intrinsics_index = -1;
  double readout_s = 0.0;
  int readout_index = -1;
  Eigen::Matrix3d D_w = Eigen::Matrix3d::Identity(), D_a = Eigen::Matrix3d::Identity();
  int imu_intrinsics_index = -1; ///< [δD_w lower triangle (00 10 11 20 21 22), δD_a likewise]
  bool estimates_camera() const { return extrinsics_index >= 0 || intrinsics_index >= 0 || readout_index >= 0; }
};

/// Lower-triangle parameter order of D_w and D_a in the state: (0,0) (1,0) (1,1) (2,0) (2,1) (2,2).
constexpr int kTriRow[6] = {0, 1, 1, 2, 2, 2};
constexpr int kTriCol[6] = {0, 0, 1, 0, 1, 2};

/// A SLAM feature: a landmark kept in the state across the window (world position, additive error δp_f), updated by
/// every new observation and marginalised when the tracker loses it. Its measurement Jacobians use its first
/// estimate (FEJ), like the clones'.
struct LandmarkState {
  static constexpr int kSize = 3;
  size_t id = 0; ///< the tracker's feature id
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_fej = Eigen::Vector3d::Zero();
  int index = -1;
  int64_t t_init_ns = 0; ///< camera stamp of the image it was initialised at
  int updates = 0;       ///< observations that updated it
};

/// Camera k ≥ 1's own time offset (time_offset.per_camera): its t_d is cam0's plus Δ_k. Why a difference rather
/// than an absolute offset: every mode's treatment of cam0's t_d (sr's clone placement, the image-plane shift, the
/// drift and TPN models) then carries over to camera k's rows unchanged, and camera k's rows gain one column, V·Δ_k,
/// in every mode; with Δ_k = 0 and no variable the rig shares one t_d exactly as before.
struct CameraTdState {
  double delta = 0.0; ///< Δ_k [s]
  int index = -1;     ///< covariance index of δΔ_k
  double rate = 0.0;  ///< Δ̇_k [s/s], a state variable only with per_camera_rate (rate_index >= 0)
  int rate_index = -1;
};

/// The scalar of the covariance a State::for_each_covariance function receives.
template <class M> using covariance_scalar = typename std::decay_t<M>::Scalar;

class State {
public:
  /// estimate_td: t_d gets a covariance entry (modes sr, sir, fvon, tpn, ton); otherwise it is a fixed parameter.
  explicit State(bool estimate_td = true);

  ImuState imu;
  int64_t t_imu_ns = 0; ///< time the IMU state refers to
  double td = 0.0;
  int td_index = -1;    ///< -1 when t_d is not estimated
  double td_rate = 0.0; ///< ṫ_d [s/s]; a state variable only when td_rate_index >= 0 (drift-state model)
  int td_rate_index = -1;
  /// Cameras 1, 2, ... by cam − 1 (time_offset.per_camera); empty: the rig shares t_d.
  std::vector<CameraTdState> cam_td;
  std::map<int64_t, CloneState> clones;
  std::map<size_t, LandmarkState> landmarks; ///< by feature id
  CalibState calib;
  Eigen::MatrixXd P;
  /// The covariance the run reports (trajectory sigmas, NEES) when the filter's weights are not its error model:
  /// the error covariance of the filter's own gains under a model of the track errors (update.
  /// covariance_track_correlation, slam.covariance_sigma_px). The gains and gates use P; every operation on P
  /// applies to P_report alike (the same Φ, Q, cloning, marginalisation), the updates with the Joseph form of P's
  /// gain under the model's noise (state_helper::ekf_update). Empty: P is both.
  /// Double precision like P: after a dynamic initialisation P's eigenvalues span ~5e8 (velocity and gravity
  /// against t_d and the biases), beyond float's 1e7, and a float P_report lost positive definiteness within a
  /// second (t_d's variance negative, clamped to a sigma of 0; docs/benchmarks.md, "The reported covariance").
  Eigen::MatrixXd P_report;

  int dim() const { return static_cast<int>(P.rows()); }
  bool separate_report() const { return P_report.size() != 0; }
  /// Starts the reported covariance at the filter's P.
  void start_report() { P_report = P; }
  /// A block of the covariance the run reports (P_report where kept, else P), in double.
  Eigen::MatrixXd reported_block(int row, int col, int rows, int cols) const {
    return separate_report() ? Eigen::MatrixXd(P_report.block(row, col, rows, cols))
                             : Eigen::MatrixXd(P.block(row, col, rows, cols));
  }
  /// P, then P_report when it is kept: for the operations that act on both alike (`f` takes either matrix type;
  /// covariance_scalar names the one it got).
  template <class F> void for_each_covariance(F &&f) {
    f(P);
    if (separate_report())
      f(P_report);
  }
  bool estimates_td() const { return td_index >= 0; }
  double td_sigma() const { return estimates_td() ? std::sqrt(std::max(0.0, P(td_index, td_index))) : 0.0; }
  /// t_d's sigma in the covariance the run reports.
  double reported_td_sigma() const {
    if (!estimates_td() || !separate_report())
      return td_sigma();
    return std::sqrt(std::max(0.0, P_report(td_index, td_index)));
  }
  double td_variance() const { return estimates_td() ? P(td_index, td_index) : 0.0; }
  /// Whether camera `cam`'s rows carry a Δ column of their own (cam ≥ 1 with time_offset.per_camera).
  bool has_camera_td(int cam) const { return cam > 0 && static_cast<size_t>(cam) <= cam_td.size(); }
  /// Camera `cam`'s t_d: t_d + Δ_cam, or the rig's t_d.
  double td_of_camera(int cam) const { return has_camera_td(cam) ? td + cam_td[cam - 1].delta : td; }
  /// Its sigma in the covariance the run reports: var(t_d) + var(Δ) + 2 cov(t_d, Δ).
  double reported_td_sigma_of_camera(int cam) const {
    if (!has_camera_td(cam))
      return reported_td_sigma();
    const int d = cam_td[cam - 1].index;
    const auto var = [&](const auto &C) {
      return static_cast<double>(C(td_index, td_index) + C(d, d) + 2.0 * C(td_index, d));
    };
    return std::sqrt(std::max(0.0, separate_report() ? var(P_report) : var(P)));
  }
  /// t_d at clone c's image minus the t̂_d the clone was placed with (td_ref): an image-plane observation is shifted
  /// by V times this. Where a model drives t_d at td_rate without a state for the rate (TPN with
  /// time_offset.clone_trend), an older image was taken when t_d was td_rate·age smaller; otherwise the whole window
  /// shares one t_d (the drift state's rate is not applied here: its rows would need a rate column).
  double td_offset_at(const CloneState &c) const {
    const double trend = td_rate_index < 0 ? td_rate : 0.0;
    return td - trend * 1e-9 * static_cast<double>(t_imu_ns - c.t_imu_ns) - c.td_ref;
  }

  /// Appends a variable of `size` error dimensions with prior covariance `prior` (uncorrelated with the rest);
  /// returns its index. Clones keep their indices (they are appended by state_helper::clone the same way).
  int add_variable(const Eigen::MatrixXd &prior);

  /// Removes the error-state block [idx, idx + size) from P and moves every variable behind it forward. The
  /// variable that owned the block must be dropped by the caller.
  void remove_block(int idx, int size);

  /// Applies an error-state correction dx (size dim()) with the convention above.
  void boxplus(const Eigen::VectorXd &dx);
};

} // namespace ovton::msckf
