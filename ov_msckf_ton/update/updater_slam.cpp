#include "ov_msckf_ton/update/updater_slam.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/state/state_helper.h"
#include "ov_msckf_ton/update/feature_jacobians.h"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>

namespace ovton::msckf {

UpdaterSLAM::UpdaterSLAM(const ovton::core::CameraCalib &calib, const UpdaterSlamOptions &opt,
                         const UpdaterMSCKF &msckf)
    : opt_(opt), msckf_(msckf), sigma_px_(opt.sigma_px > 0 ? opt.sigma_px : msckf.options().sigma_px) {
  (void)calib; // the calibration comes from the updater's view of the state (fixed or estimated)
  if (!(sigma_px_ > 0) || !(opt_.chi2_multiplier > 0))
    throw ovton::core::UsageError("UpdaterSLAM: sigma_px and chi2_multiplier must be positive");
  if (!(opt_.track_correlation >= 0 && opt_.track_correlation < 1))
    throw ovton::core::UsageError("UpdaterSLAM: track_correlation must be in [0, 1)");
  if (msckf_.options().td_velocity_debias != 0 && opt_.track_correlation != 0)
    throw ovton::core::UsageError(
        "UpdaterSLAM: td_velocity_debias assumes independent pixel errors (track_correlation 0)");
  if (!(opt_.covariance_sigma_px == 0 || opt_.covariance_sigma_px >= sigma_px_))
    throw ovton::core::UsageError("UpdaterSLAM: covariance_sigma_px must be 0 (off) or at least sigma_px");
}

void UpdaterSLAM::initialize(State &state, const std::vector<const ovton::core::Feature *> &features, int64_t t_cam_ns,
                             TdObservation td_obs, const VelocityProvider &velocities, SlamStats &stats) {
  const double sigma2 = sigma_px_ * sigma_px_;
  for (const ovton::core::Feature *f : features) {
    if (state.landmarks.count(f->id))
      continue;
    const TriangulationResult tri = msckf_.triangulate_feature(state, *f, td_obs, velocities);
    if (!tri.ok() || !msckf_.linearize(state, *f, tri.p_W, td_obs, velocities, lin_) || lin_.r.size() < 5) {
      ++stats.init_rejected;
      continue;
    }
    // A rig's clone seen by two cameras has its columns twice; the landmark's covariance blocks want them once.
    UpdaterMSCKF::merge_repeated_columns(lin_);
    // Correlated track errors: the window's rows whitened as in the MSCKF; the observations after it are then
    // differenced against their predecessor (update()), so the landmark's whole track is whitened.
    const double rho = opt_.track_correlation;
    UpdaterMSCKF::whiten_track_rows(lin_.H_x, rho);
    UpdaterMSCKF::whiten_track_rows(lin_.H_f, rho);
    UpdaterMSCKF::whiten_track_rows(lin_.r, rho);
    // Split the rows by the QR of H_f: the first three fix the landmark, the rest do not involve it.
    const Eigen::Index rows = lin_.r.size();
    const Eigen::HouseholderQR<Eigen::Matrix<double, Eigen::Dynamic, 3>> qr(lin_.H_f);
    Eigen::MatrixXd Hx = lin_.H_x;
    Eigen::VectorXd r = lin_.r;
    Hx.applyOnTheLeft(qr.householderQ().adjoint());
    r.applyOnTheLeft(qr.householderQ().adjoint());
    const Eigen::Matrix3d R1 = qr.matrixQR().topRows<3>().triangularView<Eigen::Upper>();
    // A landmark the window barely constrains along one direction would enter with a huge, badly conditioned
    // covariance: leave it to the MSCKF.
    if (R1.diagonal().cwiseAbs().minCoeff() < 1e-6 * R1.diagonal().cwiseAbs().maxCoeff()) {
      ++stats.init_rejected;
      continue;
    }
    // Both row blocks involve only the feature's columns (lin_.cols): the window's clones, t_d, the calibration.
    const Eigen::MatrixXd H1 = Hx.topRows(3);
    const Eigen::MatrixXd H2 = Hx.bottomRows(rows - 3);
    const Eigen::Vector3d r1 = r.head<3>();
    const Eigen::VectorXd r2 = r.tail(rows - 3);

    Eigen::MatrixXd S2 = H2 * state_helper::sub_covariance(state, lin_.cols) * H2.transpose();
    S2.diagonal().array() += sigma2;
    const double chi2 = r2.dot(S2.ldlt().solve(r2));
    if (!std::isfinite(chi2) || chi2 > opt_.chi2_multiplier / msckf_.options().chi2_multiplier *
                                           msckf_.chi2_threshold(static_cast<int>(r2.size()))) {
      ++stats.init_rejected;
      continue;
    }

    // The invertible part initialises the landmark with its cross-covariance to the state.
    const Eigen::Matrix3d R1inv = R1.inverse();
    LandmarkState l;
    l.id = f->id;
    l.p_W = tri.p_W + R1inv * r1;
    // First estimate in the anchor clone's first-estimate frame, as the MSCKF linearises (UpdaterMSCKF::linearize).
    const CloneState &anchor = *lin_.obs[lin_.anchor].clone;
    l.p_fej = anchor.R_lin() * (anchor.R.transpose() * (l.p_W - anchor.p)) + anchor.p_lin();
    l.t_init_ns = t_cam_ns;
    const LandmarkBlock block = landmark_block(state.P, lin_.cols, H1, R1inv, sigma2 * Eigen::Matrix3d::Identity());
    LandmarkBlock reported;
    Eigen::MatrixXd dR2; // the rest's extra noise under the reported covariance's track model
    if (state.separate_report())
      reported = report_initialization(state, lin_.cols, H1, R1inv, qr, sigma2, dR2);
    l.index = state.add_variable(block.P_ff);
    write_landmark_block(state.P, l.index, block);
    if (state.separate_report())
      write_landmark_block(state.P_report, l.index, reported);
    state.landmarks[l.id] = l;
    // The rest of the window's information, now that the landmark is in the state.
    if (r2.size() > 0) {
      // Its t_d column is the window's tracked velocities, as in an MSCKF update: the same errors-in-variables bias.
      const double bias = msckf_.td_bias_to_remove(lin_, *f, velocities, qr);
      state_helper::ekf_update(state, lin_.cols, H2, r2, sigma2, {dR2.size() ? &dR2 : nullptr, nullptr});
      UpdaterMSCKF::remove_td_bias(state, bias);
    }
    ++stats.initialised;
  }
}

template <class Mat>
UpdaterSLAM::LandmarkBlock UpdaterSLAM::landmark_block(const Mat &C, const std::vector<int> &cols,
                                                       const Eigen::MatrixXd &H1, const Eigen::Matrix3d &R1inv,
                                                       const Eigen::Matrix3d &N1) {
  const Eigen::Index n = C.rows();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, 3); // C H₁ᵀ, n × 3
  for (size_t j = 0; j < cols.size(); ++j)
    M.noalias() += C.col(cols[j]).template cast<double>() * H1.col(static_cast<Eigen::Index>(j)).transpose();
  Eigen::Matrix3d S1 = Eigen::Matrix3d::Zero();
  for (size_t j = 0; j < cols.size(); ++j)
    S1.noalias() += H1.col(static_cast<Eigen::Index>(j)) * M.row(cols[j]);
  S1 += N1;
  return {-M * R1inv.transpose(), R1inv * S1 * R1inv.transpose()};
}

template <class Mat> void UpdaterSLAM::write_landmark_block(Mat &C, int index, const LandmarkBlock &b) {
  using T = typename Mat::Scalar;
  const Eigen::Index n = b.P_xf.rows();
  C.block(0, index, n, 3) = b.P_xf.cast<T>();
  C.block(index, 0, 3, n) = b.P_xf.transpose().cast<T>();
  C.template block<3, 3>(index, index) = b.P_ff.cast<T>();
}

UpdaterSLAM::LandmarkBlock UpdaterSLAM::report_initialization(const State &state, const std::vector<int> &cols,
                                                              const Eigen::MatrixXd &H1, const Eigen::Matrix3d &R1inv,
                                                              const UpdaterMSCKF::FeatureQR &qr, double sigma2,
                                                              Eigen::MatrixXd &dR2) const {
  // The window's rows under the MSCKF's track model (AR(1) ρ_c; independent when 0): noise σ²·(QᵀL)(QᵀL)ᵀ split
  // like the rows, σ²B₁B₁ᵀ for the three that fix the landmark. (n₁'s correlation with the rest's noise n₂ is left
  // out.)
  // A rig's window: by image times and cameras (UpdaterMSCKF::rig_track_correlation).
  const Eigen::Index rows = qr.rows();
  const UpdaterMSCKFOptions &mo = msckf_.options();
  if (UpdaterMSCKF::seen_by_further_camera(lin_)) {
    const Eigen::MatrixXd M = UpdaterMSCKF::projected_rig_track_covariance(
        qr,
        UpdaterMSCKF::rig_track_correlation(lin_, mo.covariance_track_correlation, mo.covariance_camera_correlation));
    dR2 = sigma2 * M.bottomRightCorner(rows - 3, rows - 3);
    dR2.diagonal().array() -= sigma2;
    return landmark_block(state.P_report, cols, H1, R1inv, sigma2 * M.topLeftCorner<3, 3>());
  }
  Eigen::MatrixXd B = UpdaterMSCKF::track_noise_factor(rows, mo.covariance_track_correlation);
  B.applyOnTheLeft(qr.householderQ().adjoint());
  dR2 = sigma2 * B.bottomRows(rows - 3) * B.bottomRows(rows - 3).transpose();
  dR2.diagonal().array() -= sigma2;
  return landmark_block(state.P_report, cols, H1, R1inv, sigma2 * B.topRows(3) * B.topRows(3).transpose());
}

bool UpdaterSLAM::linearize(const UpdaterMSCKF::CameraView &view, const State &state, const LandmarkState &l,
                            const CloneState &c, const ovton::core::Feature &feature, size_t obs_index,
                            TdObservation td_obs, const VelocityProvider &velocities, LandmarkLinearization &out,
                            const BodyMotion *motion) const {
  Eigen::Vector2d zhat, z_lin;
  Eigen::Vector3d p_C;
  CloneMeasurementJacobians J;
  if (!project_in_clone(c.R, c.p, view.R_BC, view.p_BC, l.p_W, zhat, &p_C) ||
      !project_in_clone(c.R_lin(), c.p_lin(), view.R_BC, view.p_BC, l.p_fej, z_lin, nullptr, &J))
    return false;
  out.depth = p_C.z();
  if (out.depth < opt_.min_depth || out.depth > opt_.max_depth)
    return false;
  const ovton::core::FeatureObservation &o = feature.obs[obs_index];
  Eigen::Vector2d vel;
  int src = kVelocityNone;
  const bool predicted = motion && opt_.state_velocity && td_obs == TdObservation::ImagePlane &&
                         predicted_image_velocity(c.R, c.p, view.R_BC, view.p_BC, l.p_W, *motion, vel);
  const bool has_vel = predicted || velocities.velocity(feature, obs_index, vel, src);
  // A further camera's row without a velocity would deny the shift t_d (or its own Δ) gives the others: left out.
  const bool own_delta = state.has_camera_td(view.index);
  if (view.index > 0 && !has_vel && (td_obs == TdObservation::ImagePlane || own_delta))
    return false;
  out.td_column = td_obs == TdObservation::ImagePlane && state.estimates_td() && has_vel;
  Eigen::Vector2d shift = Eigen::Vector2d::Zero();
  if (out.td_column)
    shift += vel * state.td_offset_at(c);
  out.delta_index = own_delta ? state.cam_td[static_cast<size_t>(view.index - 1)].index : -1;
  if (own_delta)
    shift += vel * state.cam_td[static_cast<size_t>(view.index - 1)].delta;
  // The rolling shutter's shift, with the velocity UpdaterMSCKF::readout_velocity chooses (the state's prediction at
  // this clone's own motion, by default).
  const double rho = UpdaterMSCKF::row_factor(view, o);
  Eigen::Vector2d vel_ro;
  CloneMeasurementJacobians Jv = CloneMeasurementJacobians::zero();
  const bool has_ro = (view.readout_s != 0.0 || view.est_readout) &&
                      msckf_.readout_velocity(view, c, l.p_W, l.p_fej, vel, has_vel, vel_ro, &Jv);
  if (view.readout_s != 0.0 && has_ro)
    shift += vel_ro * (view.readout_s * rho);
  // Pixel rows, as the MSCKF (UpdaterMSCKF::linearize): scaled by the distortion Jacobian at the observation, or
  // the raw pixel when the intrinsics are estimated.
  Eigen::Matrix2d Jd;
  Eigen::Vector2d zs;
  if (view.est_intr) {
    zs = zhat + shift;
    out.r = o.uv - view.cam->distort(zs, &Jd);
  } else {
    view.cam->distort(o.xy, &Jd);
    out.r = Jd * (o.xy - shift - zhat);
  }
  out.H_clone.leftCols<3>() = Jd * J.H_theta;
  out.H_clone.rightCols<3>() = Jd * J.H_p;
  out.H_f = Jd * J.H_f;
  out.H_td = out.td_column ? Eigen::Vector2d(Jd * vel) : Eigen::Vector2d::Zero();
  out.H_delta = own_delta ? Eigen::Vector2d(Jd * vel) : Eigen::Vector2d::Zero();
  const double tr = has_ro ? view.readout_s * rho : 0.0; // the shift's dependence on the state, through V
  if (tr != 0.0) {
    out.H_clone.leftCols<3>() += tr * Jd * Jv.H_theta;
    out.H_clone.rightCols<3>() += tr * Jd * Jv.H_p;
    out.H_f += tr * Jd * Jv.H_f;
  }
  // Calibration columns, as UpdaterMSCKF::linearize.
  const CalibState &cal = state.calib;
  out.calib_cols.clear();
  const int n = (view.est_ext ? 6 : 0) + (view.est_intr ? 8 : 0) + (view.est_readout && has_ro ? 1 : 0);
  out.H_calib.setZero(2, n);
  int k = 0;
  if (view.est_ext) {
    out.H_calib.middleCols<3>(k) = Jd * J.H_ext_theta;
    out.H_calib.middleCols<3>(k + 3) = Jd * J.H_ext_p;
    if (tr != 0.0) {
      out.H_calib.middleCols<3>(k) += tr * Jd * Jv.H_ext_theta;
      out.H_calib.middleCols<3>(k + 3) += tr * Jd * Jv.H_ext_p;
    }
    for (int j = 0; j < 6; ++j)
      out.calib_cols.push_back(cal.extrinsics_index + j);
    k += 6;
  }
  if (view.est_intr) {
    out.H_calib.middleCols<8>(k) = view.cam->intrinsics_jacobian(zs);
    for (int j = 0; j < 8; ++j)
      out.calib_cols.push_back(cal.intrinsics_index + j);
    k += 8;
  }
  if (view.est_readout && has_ro) {
    out.H_calib.col(k) = Jd * vel_ro * rho;
    out.calib_cols.push_back(cal.readout_index);
  }
  return true;
}

bool UpdaterSLAM::difference_previous(const UpdaterMSCKF::CameraView &view, const State &state, const LandmarkState &l,
                                      const ovton::core::Feature &f, TdObservation td_obs,
                                      const VelocityProvider &velocities, LandmarkLinearization &lin,
                                      LandmarkLinearization &prev, int &prev_clone_index) const {
  const double rho = opt_.track_correlation;
  const size_t i = f.obs.size() - 2;
  const auto it = state.clones.find(f.obs[i].t_cam_ns);
  if (it == state.clones.end() || !linearize(view, state, l, it->second, f, i, td_obs, velocities, prev))
    return false;
  // The same columns on both sides (t_d and the readout follow the velocity's availability): else not differenced.
  if (prev.td_column != lin.td_column || prev.delta_index != lin.delta_index || prev.calib_cols != lin.calib_cols)
    return false;
  const double s = 1.0 / std::sqrt(1.0 - rho * rho);
  lin.r = (lin.r - rho * prev.r) * s;
  lin.H_clone *= s;
  lin.H_f = (lin.H_f - rho * prev.H_f) * s;
  lin.H_td = (lin.H_td - rho * prev.H_td) * s;
  lin.H_delta = (lin.H_delta - rho * prev.H_delta) * s;
  lin.H_calib = (lin.H_calib - rho * prev.H_calib) * s;
  prev.H_clone *= -rho * s;
  prev_clone_index = it->second.index;
  return true;
}

void UpdaterSLAM::update(State &state, const ovton::core::FeatureDatabase &db, int64_t t_cam_ns, TdObservation td_obs,
                         const VelocityProvider &velocities, SlamStats &stats, std::vector<size_t> &drop,
                         const BodyMotion *motion) {
  const auto clone_it = state.clones.find(t_cam_ns);
  if (clone_it == state.clones.end() || state.landmarks.empty())
    return;
  const CloneState &c = clone_it->second;
  const UpdaterMSCKF::CameraView view = msckf_.camera_view(state);
  const double sigma2 = sigma_px_ * sigma_px_;
  const double thr = opt_.chi2_multiplier / msckf_.options().chi2_multiplier * msckf_.chi2_threshold(2);
  // Each row pair involves the clone, its landmark, t_d and the calibration; the stacked system is kept over the
  // union of those columns (in state order), never over the whole state.
  std::vector<Eigen::Matrix<double, 2, Eigen::Dynamic>> rows_H;
  std::vector<std::vector<int>> rows_cols;
  std::vector<Eigen::Vector2d> rows_r;
  LandmarkLinearization lin, lin_prev;
  std::vector<int> cols;
  const double rho = opt_.track_correlation;
  // The rig's further cameras (slam.further_cameras; none otherwise): their calibration views, and eq. 2 for their
  // tracks' velocities (as in the MSCKF).
  std::vector<UpdaterMSCKF::CameraView> others;
  for (int cam = 1; opt_.further_cameras && cam < msckf_.num_cameras(); ++cam)
    others.push_back(msckf_.camera_view(state, cam));
  const VelocityProvider eq2;
  // One observation's row pair, after its chi-square test, into the stacked system. `track`: the camera's track.
  const auto add_row = [&](const UpdaterMSCKF::CameraView &v, LandmarkState &l, const ovton::core::Feature &track,
                           const VelocityProvider &vel) {
    // Correlated track errors (AR(1), ρ): the observation is differenced against the same camera's previous one,
    // z_k − ρ z_{k−1} = h_k(x) − ρ h_{k−1}(x) + w_k, whose noise w_k = e_k − ρ e_{k−1} is independent of every
    // earlier error (variance σ²(1 − ρ²)): the exact treatment while the previous image's clone is in the state.
    int prev_index = 0;
    const bool differenced = rho != 0.0 && track.obs.size() >= 2 &&
                             difference_previous(v, state, l, track, td_obs, vel, lin, lin_prev, prev_index);
    cols.clear();
    for (int j = 0; j < 6; ++j)
      cols.push_back(c.index + j);
    for (int j = 0; j < 3; ++j)
      cols.push_back(l.index + j);
    if (lin.td_column)
      cols.push_back(state.td_index);
    if (lin.delta_index >= 0)
      cols.push_back(lin.delta_index);
    cols.insert(cols.end(), lin.calib_cols.begin(), lin.calib_cols.end());
    if (differenced)
      for (int j = 0; j < 6; ++j)
        cols.push_back(prev_index + j);
    Eigen::Matrix<double, 2, Eigen::Dynamic> H(2, static_cast<Eigen::Index>(cols.size()));
    H.leftCols<6>() = lin.H_clone;
    H.middleCols<3>(6) = lin.H_f;
    int k = 9;
    if (lin.td_column)
      H.col(k++) = lin.H_td;
    if (lin.delta_index >= 0)
      H.col(k++) = lin.H_delta;
    H.middleCols(k, lin.H_calib.cols()) = lin.H_calib;
    if (differenced)
      H.rightCols<6>() = lin_prev.H_clone; // already −ρ/√(1 − ρ²) times the previous clone's block
    Eigen::Matrix2d S = H * state_helper::sub_covariance(state, cols) * H.transpose();
    S.diagonal().array() += sigma2;
    const double chi2 = lin.r.dot(S.ldlt().solve(lin.r));
    if (!std::isfinite(chi2) || chi2 > thr) {
      ++stats.gated;
      return;
    }
    rows_H.push_back(H);
    rows_cols.push_back(cols);
    rows_r.push_back(lin.r);
    ++l.updates;
  };
  for (auto &[id, l] : state.landmarks) {
    const ovton::core::Feature *f = db.get(id);
    if (!f || f->obs.empty() || f->newest().t_cam_ns != t_cam_ns)
      continue; // not seen in this image: the caller marginalises it
    if (!linearize(view, state, l, c, *f, f->obs.size() - 1, td_obs, velocities, lin, motion)) {
      drop.push_back(id);
      continue;
    }
    add_row(view, l, *f, velocities);
    // The same landmark in the further cameras' images of this instant (their stamp is the primary's). A row that
    // cannot be linearised there is left out; the landmark stays (the primary camera decides).
    for (size_t k = 0; k < f->more.size() && k < others.size(); ++k) {
      const ovton::core::Feature &track = f->more[k];
      if (track.obs.empty() || track.newest().t_cam_ns != t_cam_ns ||
          !linearize(others[k], state, l, c, track, track.obs.size() - 1, td_obs, eq2, lin, motion))
        continue;
      add_row(others[k], l, track, eq2);
    }
  }
  if (rows_r.empty())
    return;
  cols.clear();
  for (const auto &rc : rows_cols)
    cols.insert(cols.end(), rc.begin(), rc.end());
  std::sort(cols.begin(), cols.end());
  cols.erase(std::unique(cols.begin(), cols.end()), cols.end());
  std::vector<int> where(static_cast<size_t>(state.dim()), -1);
  for (size_t j = 0; j < cols.size(); ++j)
    where[cols[j]] = static_cast<int>(j);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(2 * static_cast<Eigen::Index>(rows_r.size()), cols.size());
  Eigen::VectorXd r(2 * rows_r.size());
  for (size_t k = 0; k < rows_r.size(); ++k) {
    for (size_t j = 0; j < rows_cols[k].size(); ++j)
      H.block<2, 1>(2 * k, where[rows_cols[k][j]]) += rows_H[k].col(static_cast<Eigen::Index>(j));
    r.segment<2>(2 * k) = rows_r[k];
  }
  UpdaterMSCKF::compress(H, r);
  if (state.separate_report() && opt_.covariance_sigma_px > sigma_px_) {
    // Independent rows of σ_c² under the σ² gain (the compression keeps a multiple of I as it is).
    const Eigen::MatrixXd dR =
        Eigen::MatrixXd::Identity(r.size(), r.size()) * (opt_.covariance_sigma_px * opt_.covariance_sigma_px - sigma2);
    state_helper::ekf_update(state, cols, H, r, sigma2, {&dR, nullptr});
  } else {
    state_helper::ekf_update(state, cols, H, r, sigma2);
  }
  stats.updated += static_cast<int>(rows_r.size());
}

} // namespace ovton::msckf
