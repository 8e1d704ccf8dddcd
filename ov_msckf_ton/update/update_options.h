#pragma once
// Options of the two feature updaters, nested in the estimator's options tree (core/vio_options.h, sections `update`
// and `slam`; two keys live elsewhere in the YAML: time_offset.velocity_debias and calibration.readout_state_velocity).

namespace ovton::msckf {

struct UpdaterMSCKFOptions {
  double sigma_px = 1.0;         ///< measurement noise [px], converted by the mean focal length
  double chi2_multiplier = 1.0;  ///< scales the chi-square threshold (OpenVINS' chi2_multipler)
  double chi2_confidence = 0.95; ///< quantile of the chi-square gate
  int min_observations = 3;      ///< observations with a clone a feature needs to be used (update.min_track_length)
  double min_depth = 0.1;        ///< [m]
  double max_depth = 60.0;       ///< [m]
  int max_features = 80;         ///< per update, longest tracks first; 0 = no limit
  double min_parallax_deg = 0.2; ///< triangulation: below this the depth is noise
  double max_reproj_px = 10.0;   ///< triangulation: RMS reprojection error
  int triangulation_max_iterations = 20;
  /// ρ of the AR(1) model of a track's pixel errors between consecutive observations (u and v apart): the feature's
  /// rows are whitened before the nullspace projection. 0: independent errors (σ²I).
  double track_correlation = 0.0;
  /// ρ of the AR(1) model of a track's errors under which the reported covariance (State::P_report) is updated,
  /// while the gain keeps the independent σ_px weight (state_helper::ekf_update's ReportNoise: the Joseph form of
  /// that gain's error). KLT's errors are correlated from image to image; whitening them in the gain
  /// (track_correlation) costs accuracy on long flights (docs/consistency_images.md), ignoring them leaves the
  /// covariance overconfident. 0: off. Only with track_correlation 0. Needs a state with a reported covariance
  /// (VioManager keeps one then).
  double covariance_track_correlation = 0.0;
  /// A rig's cross-camera correlation in that model: a further camera finds its features by KLT from the primary's
  /// image at the same instant (ov_core/track/track_stereo.h), so the cameras' errors of one feature are correlated.
  /// Rows of observations at a feature's image times k and j correlate by ρ^|k − j| per coordinate, times this when
  /// two cameras made them (separable, so positive definite). 0: the cameras independent. Acts only with
  /// covariance_track_correlation on and only on features seen by more than one camera (monocular runs unchanged).
  double covariance_camera_correlation = 0.0;
  /// Image-plane t_d rows: take out the bias a tracked velocity puts into t̂_d. The t_d column V_k of a row is a
  /// difference of the track's measured points, so its noise correlates with the residuals' (errors in variables):
  /// eq. 2's V_k contains observation k's own noise, the central difference its neighbours', and the nullspace
  /// projection mixes rows. With D the map from the rows' pixel noise n to the noise of the t_d column (from each
  /// velocity's VelocityStencil) and independent errors of the declared σ, E[hᵀr] over a feature's projected rows
  /// gains σ²·tr(Q₂ᵀDQ₂) whatever t_d is; the update's information vector for t_d is off by b = Σ_f tr(Q₂ᵀDQ₂),
  /// and its correction by P⁺·e_td·b, which is subtracted after the update.
  /// The value scales b: the covariance of a point's error with its change since the previous image, over σ².
  /// 1 for independent errors of the declared σ (feature-level simulations); larger when the true errors are.
  /// For errors with lag-one correlation ρ the backward difference's share is σ_true²(1 − ρ)/σ² (≈ 0.03 for KLT on
  /// the renders: σ 0.36 px, ρ ≈ 0.8, weighted as 1 px) and the central difference's ~0: negligible, so 0 (off)
  /// for images. Only with track_correlation 0. Not covered: landmark updates that use tracked velocities
  /// (slam.state_velocity off), the readout column's velocity.
  double td_velocity_debias = 0.0;
  /// Rolling shutter: a row's shift V·ρ·t_r takes the image velocity the state predicts (the triangulated point, the
  /// clone's pose and the motion it was cloned with; predicted_image_velocity) instead of the track's measured one,
  /// whose pixel noise is the row's own and which a track's first observation lacks. Every row then carries the
  /// readout column, with V's dependence on the pose, the point and the extrinsics in its Jacobians.
  bool readout_state_velocity = true;
};

/// SLAM features (updater_slam.h): landmarks in the state, re-observed at every image.
struct UpdaterSlamOptions {
  double sigma_px = 0.0; ///< pixel noise of a landmark observation; 0: the MSCKF updater's sigma_px
  double chi2_multiplier = 1.0;
  double min_depth = 0.1, max_depth = 60.0; ///< [m]: a landmark leaving this range is marginalised
  /// ρ of the AR(1) model of a landmark's pixel errors between consecutive images: its window rows are whitened at
  /// initialisation, each later observation differenced against the one before. 0: independent errors.
  double track_correlation = 0.0;
  /// Pixel noise [px] under which a landmark's re-observations update the covariance, while the gain keeps sigma_px
  /// (state_helper::ekf_update's ReportNoise): the long-run σ of a wandering track error that each image's
  /// observation repeats. 0: sigma_px (off).
  double covariance_sigma_px = 0.0;
  /// Image-plane modes: a landmark's row takes the image velocity its state predicts (landmark, camera pose,
  /// body rate and velocity at the image) instead of the tracked one. A landmark is always updated with its newest
  /// observation, where the tracked velocity is the backward difference of eq. 2, whose pixel noise is also the
  /// row's own (errors in variables): with 25 landmarks that bias drove TPN's t_d 5-9 ms ahead of a 0.5 ms/s drift.
  bool state_velocity = true;
  /// A rig's further cameras update the landmarks they see in the newest image too (one row pair per camera). Off by
  /// default: on the eight stereo peer renders it cost +3.7 % APE on average (docs/stereo.md), probably because a
  /// further camera's observation is found by KLT from the primary's at the same instant, so the two rows' errors are
  /// correlated while the update takes them as independent.
  bool further_cameras = false;
};

} // namespace ovton::msckf
