#pragma once
// The MSCKF update (Mourikis & Roumeliotis 2007, as in OpenVINS): triangulate each feature from the clone poses,
// linearise its measurements w.r.t. the clones (and t_d), remove the feature by projecting onto the left nullspace
// of its Jacobian, gate by chi-square, stack, compress and apply one EKF update.
#include "ov_core/cam/camera_calib.h"
#include "ov_core/cam/camera_model.h"
#include "ov_core/track/feature_database.h"
#include "ov_msckf_ton/state/state.h"
#include "ov_msckf_ton/update/feature_jacobians.h"
#include "ov_msckf_ton/update/residual_log.h"
#include "ov_msckf_ton/update/td_observation.h"
#include "ov_msckf_ton/update/triangulation.h"
#include "ov_msckf_ton/update/update_options.h"

#include <Eigen/Core>
#include <Eigen/QR>
#include <array>
#include <optional>
#include <vector>

namespace ovton::msckf {

struct UpdateStats {
  int features_in = 0;
  int too_few_observations = 0; ///< fewer than min_observations observations with a clone
  int over_limit = 0;           ///< dropped by max_features
  int rejected_triangulation = 0;
  /// Of those, rejected for too little parallax (LowParallax, or IllConditioned: the rays' spread too small in some
  /// direction): bearings that agree once rotation is undone carry no depth and say nothing against the state (a
  /// camera standing still or only turning), unlike a bad depth or reprojection.
  int low_parallax = 0;
  int gated_chi2 = 0;
  int features_used = 0;
  int rows_stacked = 0; ///< rows of the accepted features after nullspace projection
  int rows_update = 0;  ///< rows of the EKF update after compression
  /// Observations of used features whose row carried a t_d entry, by VelocitySource (index 0 stays 0).
  std::array<int, kNumVelocitySources> td_obs_used{};
  int td_features_used = 0; ///< used features with at least one t_d entry
  double td_debias_s = 0.0; ///< the t_d part of the errors-in-variables correction (td_velocity_debias) [s]
  double td_before = 0.0, td_after = 0.0;
  double mahalanobis = 0.0; ///< rᵀS⁻¹r of the final stacked update
};

/// The stacked measurement of one feature before nullspace projection. H_x is compact: its columns are the state
/// indices in `cols` (six per observing clone, then t_d when a row carries it, then each further camera's own Δ with
/// time_offset.per_camera), so the cost does not grow with the window.
struct FeatureLinearization {
  struct Obs {
    size_t obs_index = 0; ///< in the track of camera `cam` (ovton::core::Feature::more for cam > 0)
    int cam = 0;
    const CloneState *clone = nullptr; ///< points into State::clones: valid until the state changes
    Eigen::Vector2d vel_xy = Eigen::Vector2d::Zero();
    int vel_source = kVelocityNone;
    bool td_column = false;
    double depth = 0.0;
    Eigen::Matrix2d Jd = Eigen::Matrix2d::Identity(); ///< d(distorted pixel)/d(normalised point) at the observation
    Eigen::Vector2d vel_readout = Eigen::Vector2d::Zero(); ///< the velocity of the rolling-shutter shift
    bool has_readout_vel = false;
  };
  /// Columns may repeat (a clone seen by two cameras of a rig has six per observation): sums of repeats are what
  /// count (merge_repeated_columns).
  std::vector<int> cols;
  int anchor = 0;                               ///< obs index of the anchor: the primary camera's newest
  Eigen::MatrixXd H_x;                          ///< 2m × cols.size()
  Eigen::Matrix<double, Eigen::Dynamic, 3> H_f; ///< 2m × 3, w.r.t. the world feature position
  Eigen::VectorXd r;                            ///< 2m, z − h(x̂, p̂_f) in normalised units
  std::vector<Obs> obs;
};

/// Not thread-safe: const methods share scratch buffers. Use one updater per filter.
class UpdaterMSCKF {
public:
  /// `more`: the rig's further cameras (Feature::more), with calibration fixed at these values.
  explicit UpdaterMSCKF(const ovton::core::CameraCalib &calib, const UpdaterMSCKFOptions &options = {},
                        std::vector<ovton::core::CameraCalib> more = {});

  /// One MSCKF update with the given features (typically lost ones and those observed in the clone that leaves the
  /// window). Observations without a clone are ignored. Appends one ResidualRecord per observation of each feature
  /// that reached triangulation to `log` when given. Throws ovton::core::UsageError on inconsistent input.
  UpdateStats update(State &state, const std::vector<const ovton::core::Feature *> &features, TdObservation td_obs,
                     const VelocityProvider &velocities, std::vector<ResidualRecord> *log = nullptr);

  /// Triangulates a feature from the current clone estimates, shifting image-plane observations by V·(t̂_d − td_ref)
  /// in ImagePlane mode so that the point agrees with the model it will be linearised in.
  TriangulationResult triangulate_feature(const State &state, const ovton::core::Feature &feature, TdObservation td_obs,
                                          const VelocityProvider &velocities) const;

  /// Residuals and Jacobians of every observation of `feature` that has a clone, at the feature position p_f:
  ///   r_i = z_i − h(clone_i, p_f) − V_i·(t̂_d − td_ref_i)     (the V term only in ImagePlane mode with a velocity)
  ///   H_x: [∂h/∂δθ_i  ∂h/∂δp_i] per clone (feature_jacobians.h), and +V_i in the t_d column (paper eq. 1: the
  ///        shifted measurement z − V·(t_d − td_ref) has Jacobian −V, so the model z = h + V·(t_d − td_ref) has +V).
  ///   A further camera k with its own offset (State::cam_td) adds V_i·Δ_k to the model of its rows in every mode
  ///   (its image came Δ_k after cam0's of the same stamp): +V_i in Δ_k's column.
  /// Returns false when the point is behind a camera.
  bool linearize(const State &state, const ovton::core::Feature &feature, const Eigen::Vector3d &p_f,
                 TdObservation td_obs, const VelocityProvider &velocities, FeatureLinearization &out) const;

  /// Multiplies H_x and r on the left by Q₂ᵀ, where [Q₁ Q₂] is the Householder QR of H_f (2m × 3, full column rank),
  /// so that Q₂ᵀH_f = 0: the result no longer depends on the feature error. Rows become 2m − 3. Noise stays σ²I
  /// because Q₂ has orthonormal columns.
  static void nullspace_project(const Eigen::Matrix<double, Eigen::Dynamic, 3> &H_f, Eigen::MatrixXd &H_x,
                                Eigen::VectorXd &r);
  /// The same with H_f's QR already made (the update makes it once for this and projected_innovation).
  using FeatureQR = Eigen::HouseholderQR<Eigen::Matrix<double, Eigen::Dynamic, 3>>;
  static void nullspace_project(const FeatureQR &qr, Eigen::MatrixXd &H_x, Eigen::VectorXd &r);
  /// When H has more rows than columns, replaces (H, r) by (R, Q₁ᵀr) of H's QR: the same information in at most
  /// dim rows, noise still σ²I.
  static void compress(Eigen::MatrixXd &H, Eigen::VectorXd &r);
  /// Sums the H_x columns that name the same state index into one (a rig: clones seen by several cameras).
  static void merge_repeated_columns(FeatureLinearization &lin);
  /// L with L Lᵀ = C, the AR(1) correlation of a track's stacked rows (C_ij = ρ^|i−j| per coordinate; rows even).
  static Eigen::MatrixXd track_noise_factor(Eigen::Index rows, double rho);
  /// The noise factor of one feature's nullspace-projected rows for AR(1) errors (covariance_track_correlation):
  /// B = Q₂ᵀ L, so that the projected rows' noise is σ²BBᵀ.
  static Eigen::MatrixXd projected_track_noise_factor(const FeatureQR &qr, double rho);
  /// The correlation C of a rig's feature's stacked rows (linearize's order) under the reported covariance's model
  /// (covariance_track_correlation ρ, covariance_camera_correlation ρ_cam): per coordinate
  /// C = ρ^|k_a − k_b| · (ρ_cam when observations a and b are of different cameras), k the rank of an observation's
  /// image time among the feature's. A principal block of (1 ρ_cam; ρ_cam 1) ⊗ AR(1), so positive definite. With one
  /// camera it is track_noise_factor's L Lᵀ when the track has no gaps.
  static Eigen::MatrixXd rig_track_correlation(const FeatureLinearization &lin, double rho, double rho_cam);
  /// Whether a further camera observed the feature (its rows then repeat clone columns and take the rig's track model).
  static bool seen_by_further_camera(const FeatureLinearization &lin);
  /// Sums the columns of H that belong to the same state column (a rig's clone seen by several cameras), in their
  /// order, leaving each state column once in `cols` (in order of first appearance): what stacking them adds anyway.
  static void merge_repeated_columns(std::vector<int> &cols, Eigen::MatrixXd &H);
  /// Qᵀ C Q for the feature's H_f QR (its bottom-right 2m − 3 block: the projected rows' noise over σ²; the top-left
  /// 3: the rows that fix a landmark's position).
  static Eigen::MatrixXd projected_rig_track_covariance(const FeatureQR &qr, Eigen::MatrixXd C);
  /// The innovation covariance of the nullspace-projected rows, S = Q₂ᵀ H_x P Hₓᵀ Q₂ + σ²I ((2m − 3) square), from
  /// H_x's structure (linearize's layout: clone k's six columns 6k..6k+5 are non-zero only in rows 2k, 2k + 1; the
  /// columns after 6m are dense): H_x P Hₓᵀ costs O(m²) for the clone blocks instead of O(m·(6m)²) with the
  /// projected, dense rows. P_sub is P over lin.cols.
  static Eigen::MatrixXd projected_innovation(const FeatureLinearization &lin, const Eigen::MatrixXd &P_sub,
                                              double sigma2, double rho = 0.0);
  /// The same with the QR of lin.H_f (its rows whitened when rho != 0) already made.
  static Eigen::MatrixXd projected_innovation(const FeatureLinearization &lin, const FeatureQR &qr,
                                              const Eigen::MatrixXd &P_sub, double sigma2, double rho);
  /// Whitens the rows of one feature's stacked measurement (2m rows: u and v of observation k at 2k, 2k + 1) for
  /// AR(1) errors with correlation ρ between consecutive observations: row k becomes (row k − ρ·row k−1)/√(1 − ρ²),
  /// row 0 stays. Errors of covariance σ²·C (C_ij = ρ^|i−j| per coordinate) then have covariance σ²I.
  static void whiten_track_rows(Eigen::Ref<Eigen::MatrixXd> M, double rho);

  /// tr(Q₂ᵀDQ₂) of one linearised feature (td_velocity_debias): the expected spurious part of hᵀr/σ² over its
  /// projected rows, h its t_d column. 0 when its rows carry no t_d column.
  static double td_velocity_bias(const FeatureLinearization &lin, const ovton::core::Feature &feature,
                                 const VelocityProvider &velocities, const FeatureQR &qr);
  /// td_velocity_debias × td_velocity_bias: what an update with this feature is to remove (0 when off or when the
  /// feature's rows carry no t_d column, i.e. outside the image-plane modes).
  double td_bias_to_remove(const FeatureLinearization &lin, const ovton::core::Feature &feature,
                           const VelocityProvider &velocities, const FeatureQR &qr) const;
  /// After an EKF update whose t_d information vector was off by `bias` (Σ td_velocity_bias): the state moves by
  /// −P⁺·e_td·bias (the gain's information form, P⁺Hᵀr/σ²). Returns the change of t̂_d.
  static double remove_td_bias(State &state, double bias);

  /// chi2_multiplier × the chi-square quantile at chi2_confidence for `dof` degrees of freedom (cached table).
  double chi2_threshold(int dof) const;
  /// d(distorted pixel)/d(normalised point) at xy: residual rows are scaled by it (noise is isotropic in pixels).
  Eigen::Matrix2d distortion_jacobian(const Eigen::Vector2d &xy) const;
  const UpdaterMSCKFOptions &options() const { return opt_; }
  /// The rig's cameras: the primary and the further ones.
  int num_cameras() const { return 1 + static_cast<int>(more_cam_.size()); }

  /// The camera calibration an update uses: the state's estimate where it is estimated (calibration.* options),
  /// the configured calibration elsewhere.
  struct CameraView {
    Eigen::Matrix3d R_BC;
    Eigen::Vector3d p_BC;
    const ovton::core::CameraModel *cam = nullptr;
    std::optional<ovton::core::CameraModel> est; ///< the state's intrinsics, when estimated
    double readout_s = 0.0;
    int height = 0;
    bool est_ext = false, est_intr = false, est_readout = false;
    int index = 0; ///< the camera in the rig (0: the primary)
  };
  /// Camera `cam` of the rig (0: the primary). The further cameras' calibration is fixed; the readout is the rig's.
  CameraView camera_view(const State &state, int cam = 0) const;
  /// The observation's undistorted normalised coordinates under the view's intrinsics.
  Eigen::Vector2d observation_xy(const CameraView &v, const ovton::core::FeatureObservation &o) const;
  /// ρ = v/H − ½: the observation's row time relative to the image's middle row, in readouts.
  static double row_factor(const CameraView &v, const ovton::core::FeatureObservation &o);
  /// The image velocity of the rolling-shutter shift at clone c for a point at p_W (readout_state_velocity), or the
  /// track's measured one (`tracked`, `has_tracked`). J (state velocity only): its Jacobians, at (R_lin, p_lin,
  /// p_lin_f). False when there is none (no motion, behind the camera, no measured velocity).
  bool readout_velocity(const CameraView &view, const CloneState &c, const Eigen::Vector3d &p_W,
                        const Eigen::Vector3d &p_lin_f, const Eigen::Vector2d &tracked, bool has_tracked,
                        Eigen::Vector2d &vel, CloneMeasurementJacobians *J) const;

  /// One observation with a clone: its index in camera `cam`'s track.
  struct Usable {
    size_t obs_index;
    const CloneState *clone;
    int cam;
  };

private:
  /// Observations of `feature` that have a clone: the primary camera's first, then each further camera's. In the
  /// image-plane mode a further camera's observation needs its own velocity (eq. 2): without one its rows would
  /// deny t_d's shift of the others (the all-or-nothing rule of linearize), so it is left out; so it is in every mode
  /// when the camera has its own offset (its rows need V for Δ's column).
  void usable_observations(const State &state, const ovton::core::Feature &feature, TdObservation td_obs,
                           std::vector<Usable> &out) const;
  /// The velocity of a usable observation: `velocities` for the primary camera, eq. 2 for the others.
  bool velocity_of(const VelocityProvider &velocities, const ovton::core::Feature &feature, const Usable &u,
                   Eigen::Vector2d &vel, int &src) const;
  void append_records(const State &state, const ovton::core::Feature &feature, const FeatureLinearization *lin,
                      const std::vector<Usable> &usable, TdObservation td_obs, const VelocityProvider &velocities,
                      const Eigen::Vector3d &p_f, double chi2, double threshold, ResidualStatus status,
                      std::vector<ResidualRecord> &log) const;

  ovton::core::CameraCalib calib_;
  UpdaterMSCKFOptions opt_;
  Eigen::Matrix3d R_BC_;
  Eigen::Vector3d p_BC_;
  ovton::core::CameraModel camera_;
  std::vector<ovton::core::CameraCalib> more_calib_;
  std::vector<ovton::core::CameraModel> more_cam_;
  VelocityProvider tracked_;       ///< eq. 2, for the further cameras' tracks
  std::vector<double> chi2_table_; ///< index = dof
  uint64_t update_count_ = 0;

  // Scratch reused across features and updates.
  mutable std::vector<Usable> usable_;
  mutable std::vector<CameraPose> poses_;
  mutable std::vector<Eigen::Vector2d> xy_;
  FeatureLinearization lin_;
  Eigen::Matrix<double, Eigen::Dynamic, 3> H_f_white_; ///< H_f with whitened rows (track_correlation)
  FeatureQR qr_;                                       ///< the feature's H_f QR, kept to reuse its storage
  struct Accepted {
    std::vector<int> cols;
    Eigen::MatrixXd H;
    Eigen::VectorXd r;
    Eigen::MatrixXd dR; ///< the projected rows' extra noise for the reported covariance (covariance_track_correlation)
  };
  std::vector<Accepted> accepted_;
  std::vector<int> cols_, where_;      ///< the stacked system's state columns, and each state column's place in it
  mutable std::vector<int> delta_col_; ///< linearize: each camera's Δ column in the feature's H_x (per_camera)
};

} // namespace ovton::msckf
