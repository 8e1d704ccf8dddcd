#include "ov_msckf_ton/update/updater_msckf.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/state/state_helper.h"
#include "ov_msckf_ton/update/feature_jacobians.h"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <optional>

namespace ovton::msckf {

namespace {

/// Degrees of freedom precomputed at construction: 2m − 3 rows for a window of tens of clones stays well below.
constexpr int kChi2TableSize = 500;

double chi2_quantile(double confidence, int dof) {
  const boost::math::chi_squared_distribution<double> dist(static_cast<double>(dof));
  return boost::math::quantile(dist, confidence);
}

/// The observation a usable entry names, in its camera's track.
const ovton::core::FeatureObservation &track_obs(const ovton::core::Feature &f, const UpdaterMSCKF::Usable &u) {
  return u.cam == 0 ? f.obs[u.obs_index] : f.more[static_cast<size_t>(u.cam - 1)].obs[u.obs_index];
}

} // namespace

UpdaterMSCKF::UpdaterMSCKF(const ovton::core::CameraCalib &calib, const UpdaterMSCKFOptions &options,
                           std::vector<ovton::core::CameraCalib> more)
    : calib_(calib), opt_(options), camera_(calib), more_calib_(std::move(more)) {
  for (const auto &c : more_calib_)
    more_cam_.emplace_back(c);
  const double fu = calib.intrinsics(0), fv = calib.intrinsics(1);
  if (!(fu > 0) || !(fv > 0))
    throw ovton::core::UsageError("UpdaterMSCKF: focal lengths must be positive");
  if (!(opt_.sigma_px > 0))
    throw ovton::core::UsageError("UpdaterMSCKF: sigma_px must be positive");
  if (!(opt_.chi2_confidence > 0 && opt_.chi2_confidence < 1))
    throw ovton::core::UsageError("UpdaterMSCKF: chi2_confidence must be in (0, 1)");
  if (!(opt_.chi2_multiplier > 0))
    throw ovton::core::UsageError("UpdaterMSCKF: chi2_multiplier must be positive");
  if (!(opt_.track_correlation >= 0 && opt_.track_correlation < 1))
    throw ovton::core::UsageError("UpdaterMSCKF: track_correlation must be in [0, 1)");
  if (!(opt_.td_velocity_debias >= 0 && opt_.td_velocity_debias <= 10))
    throw ovton::core::UsageError("UpdaterMSCKF: td_velocity_debias must be in [0, 10]");
  if (opt_.td_velocity_debias != 0 && opt_.track_correlation != 0)
    throw ovton::core::UsageError(
        "UpdaterMSCKF: td_velocity_debias assumes independent pixel errors (track_correlation 0)");
  if (!(opt_.covariance_track_correlation >= 0 && opt_.covariance_track_correlation < 1))
    throw ovton::core::UsageError("UpdaterMSCKF: covariance_track_correlation must be in [0, 1)");
  if (opt_.covariance_track_correlation != 0 && opt_.track_correlation != 0)
    throw ovton::core::UsageError("UpdaterMSCKF: covariance_track_correlation is for the independent weight: it needs "
                                  "track_correlation 0");
  if (!(opt_.covariance_camera_correlation >= 0 && opt_.covariance_camera_correlation < 1))
    throw ovton::core::UsageError("UpdaterMSCKF: covariance_camera_correlation must be in [0, 1)");
  if (opt_.min_observations < 2)
    throw ovton::core::UsageError("UpdaterMSCKF: min_observations must be at least 2 (two views leave one row)");
  if (!(opt_.min_depth > 0) || !(opt_.max_depth > opt_.min_depth))
    throw ovton::core::UsageError("UpdaterMSCKF: need 0 < min_depth < max_depth");
  if (opt_.max_features < 0)
    throw ovton::core::UsageError("UpdaterMSCKF: max_features must be >= 0 (0 = no limit)");
  R_BC_ = calib.T_BC.topLeftCorner<3, 3>();
  p_BC_ = calib.T_BC.topRightCorner<3, 1>();
  chi2_table_.resize(kChi2TableSize + 1, 0.0);
  for (int d = 1; d <= kChi2TableSize; ++d)
    chi2_table_[d] = opt_.chi2_multiplier * chi2_quantile(opt_.chi2_confidence, d);
}

double UpdaterMSCKF::row_factor(const CameraView &v, const ovton::core::FeatureObservation &o) {
  return o.uv.y() / static_cast<double>(v.height) - 0.5;
}

Eigen::Matrix2d UpdaterMSCKF::distortion_jacobian(const Eigen::Vector2d &xy) const {
  Eigen::Matrix2d J;
  camera_.distort(xy, &J);
  return J;
}

double UpdaterMSCKF::chi2_threshold(int dof) const {
  if (dof <= 0)
    throw ovton::core::UsageError("chi2_threshold: dof must be positive");
  if (dof <= kChi2TableSize)
    return chi2_table_[dof];
  return opt_.chi2_multiplier * chi2_quantile(opt_.chi2_confidence, dof);
}

void UpdaterMSCKF::usable_observations(const State &state, const ovton::core::Feature &feature, TdObservation td_obs,
                                       std::vector<Usable> &out) const {
  out.clear();
  for (size_t i = 0; i < feature.obs.size(); ++i) {
    const auto it = state.clones.find(feature.obs[i].t_cam_ns);
    if (it != state.clones.end())
      out.push_back({i, &it->second, 0});
  }
  for (size_t k = 0; k < feature.more.size() && k < more_cam_.size(); ++k) {
    const auto &obs = feature.more[k].obs;
    for (size_t i = 0; i < obs.size(); ++i) {
      const auto it = state.clones.find(obs[i].t_cam_ns);
      const bool needs_vel = td_obs == TdObservation::ImagePlane || state.has_camera_td(static_cast<int>(k + 1));
      if (it != state.clones.end() && (!needs_vel || obs[i].vel_valid))
        out.push_back({i, &it->second, static_cast<int>(k + 1)});
    }
  }
}

bool UpdaterMSCKF::velocity_of(const VelocityProvider &velocities, const ovton::core::Feature &feature, const Usable &u,
                               Eigen::Vector2d &vel, int &src) const {
  if (u.cam == 0)
    return velocities.velocity(feature, u.obs_index, vel, src);
  return tracked_.velocity(feature.more[static_cast<size_t>(u.cam - 1)], u.obs_index, vel, src);
}

UpdaterMSCKF::CameraView UpdaterMSCKF::camera_view(const State &state, int cam) const {
  const CalibState &c = state.calib;
  CameraView v;
  v.index = cam;
  if (cam > 0) {
    const ovton::core::CameraCalib &k = more_calib_.at(static_cast<size_t>(cam - 1));
    v.R_BC = k.T_BC.topLeftCorner<3, 3>();
    v.p_BC = k.T_BC.topRightCorner<3, 1>();
    v.cam = &more_cam_[static_cast<size_t>(cam - 1)];
    v.readout_s = c.readout_s;
    v.est_readout = c.readout_index >= 0;
    v.height = k.height;
    return v;
  }
  v.est_ext = c.extrinsics_index >= 0;
  v.est_intr = c.intrinsics_index >= 0;
  v.est_readout = c.readout_index >= 0;
  v.R_BC = v.est_ext ? c.R_BC : R_BC_;
  v.p_BC = v.est_ext ? c.p_BC : p_BC_;
  v.readout_s = c.readout_s;
  v.height = calib_.height;
  if (v.est_intr) {
    ovton::core::CameraCalib k = calib_;
    k.intrinsics = c.intrinsics.head<4>();
    k.dist_coeffs = c.intrinsics.tail<4>();
    v.est.emplace(k);
  }
  v.cam = v.est ? &*v.est : &camera_;
  return v;
}

Eigen::Vector2d UpdaterMSCKF::observation_xy(const CameraView &v, const ovton::core::FeatureObservation &o) const {
  // With the intrinsics in the state the tracker's undistortion (configured intrinsics) is stale: redo it.
  return v.est ? v.cam->undistort(o.uv) : o.xy;
}

TriangulationResult UpdaterMSCKF::triangulate_feature(const State &state, const ovton::core::Feature &feature,
                                                      TdObservation td_obs, const VelocityProvider &velocities) const {
  const CameraView primary = camera_view(state);
  usable_observations(state, feature, td_obs, usable_);
  poses_.clear();
  xy_.clear();
  size_t anchor = 0;
  std::optional<CameraView> other;
  int other_cam = 0;
  for (const Usable &u : usable_) {
    if (u.cam != 0 && u.cam != other_cam) {
      other = camera_view(state, u.cam);
      other_cam = u.cam;
    }
    const CameraView &view = u.cam == 0 ? primary : *other;
    const CloneState *c = u.clone;
    if (u.cam == 0)
      anchor = poses_.size();
    CameraPose cp;
    cp.R_WC = c->R * view.R_BC;
    cp.p_WC = c->p + c->R * view.p_BC;
    poses_.push_back(cp);
    const ovton::core::FeatureObservation &o = track_obs(feature, u);
    Eigen::Vector2d z = observation_xy(view, o);
    Eigen::Vector2d v;
    int src = 0;
    const bool has_v = velocity_of(velocities, feature, u, v, src);
    if (td_obs == TdObservation::ImagePlane && has_v)
      z -= v * state.td_offset_at(*c);
    if (state.has_camera_td(u.cam) && has_v)
      z -= v * state.cam_td[u.cam - 1].delta;
    if (view.readout_s != 0.0 && has_v)
      z -= v * (view.readout_s * row_factor(view, o));
    xy_.push_back(z);
  }
  TriangulationOptions to;
  to.min_depth = opt_.min_depth;
  to.max_depth = opt_.max_depth;
  to.min_parallax_deg = opt_.min_parallax_deg;
  to.max_reproj_rms = opt_.max_reproj_px / (0.5 * (calib_.intrinsics(0) + calib_.intrinsics(1)));
  to.max_iterations = opt_.triangulation_max_iterations;
  // The primary camera's newest observation anchors the inverse depth: it is the view the current state knows best.
  return triangulate(poses_, xy_, anchor, to);
}

bool UpdaterMSCKF::linearize(const State &state, const ovton::core::Feature &feature, const Eigen::Vector3d &p_f,
                             TdObservation td_obs, const VelocityProvider &velocities,
                             FeatureLinearization &out) const {
  const CameraView primary = camera_view(state);
  const CameraView &view = primary;
  const std::vector<Usable> &usable = usable_;
  usable_observations(state, feature, td_obs, usable_);
  const int m = static_cast<int>(usable.size());
  out.obs.resize(m);
  std::vector<CameraView> others; // the rig's further cameras, by cam - 1
  for (int cam = 1; cam <= static_cast<int>(more_cam_.size()); ++cam)
    others.push_back(camera_view(state, cam));
  const auto view_of = [&](int cam) -> const CameraView & { return cam == 0 ? primary : others[cam - 1]; };
  bool all_vel = m > 0;
  out.anchor = 0;
  for (int k = 0; k < m; ++k) {
    FeatureLinearization::Obs &o = out.obs[k];
    o.obs_index = usable[k].obs_index;
    o.clone = usable[k].clone;
    o.cam = usable[k].cam;
    if (o.cam == 0)
      out.anchor = k;
    o.vel_xy.setZero();
    o.vel_source = kVelocityNone;
    // Queried in every mode: the residual log needs the velocity to diagnose a time offset the model lacks.
    if (!velocity_of(velocities, feature, usable[k], o.vel_xy, o.vel_source)) {
      o.vel_xy.setZero();
      o.vel_source = kVelocityNone;
    }
    all_vel = all_vel && o.vel_source != kVelocityNone;
  }
  // All or nothing per feature: an observation without a velocity shifts by an unknown V·δt_d too. Giving t_d
  // columns to only some rows would tell the filter that the others stay put, a relative shift the feature position
  // cannot absorb: spurious information that pins t̂_d to td_ref. Such a feature constrains t_d only once every
  // observation has a velocity (a track that started before the window, or FVON's prediction for its first one).
  // The readout's row shift V·ρ·t_r follows the same rule.
  const bool any_td = all_vel && td_obs == TdObservation::ImagePlane && state.estimates_td();
  // FEJ: the residual uses the current clones, the Jacobians the clones' first estimates, so that every update
  // linearises a clone at the same point and the unobservable directions stay unobservable. The feature was
  // triangulated relative to the current clones; for the Jacobians it is carried rigidly with the anchor (newest)
  // clone onto that clone's first estimate (as OpenVINS does), so that the lever arms p_f − p_clone stay
  // consistent with the first-estimate poses.
  if (m == 0)
    return false;
  const CloneState &anchor = *out.obs[out.anchor].clone;
  const Eigen::Vector3d p_f_lin = anchor.R_lin() * (anchor.R.transpose() * (p_f - anchor.p)) + anchor.p_lin();
  // The rolling shutter's velocity per row; the readout column, like t_d's, on all rows of a feature or on none.
  const bool readout = view.readout_s != 0.0 || view.est_readout;
  bool all_readout = readout;
  for (FeatureLinearization::Obs &o : out.obs) {
    o.has_readout_vel = readout && readout_velocity(view_of(o.cam), *o.clone, p_f, p_f_lin, o.vel_xy,
                                                    o.vel_source != kVelocityNone, o.vel_readout, nullptr);
    all_readout = all_readout && o.has_readout_vel;
  }
  const bool readout_col = all_readout && view.est_readout;
  for (int k = 0; k < m; ++k)
    out.obs[k].td_column = any_td;
  // A further camera's own offset Δ_k (time_offset.per_camera): a column on every row of that camera, whatever the
  // mode, since those rows all have a velocity (usable_observations) and cam0's rows do not depend on Δ_k.
  std::vector<int> &delta_col = delta_col_; // by cam: this feature's Δ column, −1 without
  delta_col.assign(1 + more_cam_.size(), -1);
  const int c_delta = 6 * m + (any_td ? 1 : 0);
  int n_delta = 0;
  for (const FeatureLinearization::Obs &o : out.obs)
    if (state.has_camera_td(o.cam) && o.vel_source != kVelocityNone && delta_col[o.cam] < 0)
      delta_col[o.cam] = c_delta + n_delta++;
  // Columns: six per clone, then t_d, the cameras' Δ, the extrinsics, the intrinsics and the readout where they are
  // estimated.
  const int c_td = 6 * m, c_ext = c_delta + n_delta, c_intr = c_ext + (view.est_ext ? 6 : 0),
            c_ro = c_intr + (view.est_intr ? 8 : 0), nc = c_ro + (readout_col ? 1 : 0);
  out.cols.resize(nc);
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < 6; ++j)
      out.cols[6 * k + j] = out.obs[k].clone->index + j;
  if (any_td)
    out.cols[c_td] = state.td_index;
  for (size_t cam = 1; cam < delta_col.size(); ++cam)
    if (delta_col[cam] >= 0)
      out.cols[delta_col[cam]] = state.cam_td[cam - 1].index;
  for (int j = 0; view.est_ext && j < 6; ++j)
    out.cols[c_ext + j] = state.calib.extrinsics_index + j;
  for (int j = 0; view.est_intr && j < 8; ++j)
    out.cols[c_intr + j] = state.calib.intrinsics_index + j;
  if (readout_col)
    out.cols[c_ro] = state.calib.readout_index;
  out.H_x.setZero(2 * m, nc);
  out.H_f.resize(2 * m, 3);
  out.r.resize(2 * m);

  CloneMeasurementJacobians J, Jv;
  Eigen::Vector2d zhat, z_lin;
  Eigen::Vector3d p_C;
  for (int k = 0; k < m; ++k) {
    FeatureLinearization::Obs &o = out.obs[k];
    const CloneState &c = *o.clone;
    const CameraView &view = view_of(o.cam);
    if (!project_in_clone(c.R, c.p, view.R_BC, view.p_BC, p_f, zhat, &p_C) ||
        !project_in_clone(c.R_lin(), c.p_lin(), view.R_BC, view.p_BC, p_f_lin, z_lin, nullptr, &J))
      return false;
    o.depth = p_C.z();
    const ovton::core::FeatureObservation &obs = track_obs(feature, usable[k]);
    // The extrinsics and intrinsics in the state are the primary camera's: the others' rows have no such columns.
    const bool ext_cols = view.est_ext, intr_cols = view.est_intr;
    // The image-plane shifts: the image was taken when the point was V·(t_d − td_ref) away, and row v of it
    // V·ρ·t_r later (rolling shutter).
    Eigen::Vector2d shift = Eigen::Vector2d::Zero();
    if (td_obs == TdObservation::ImagePlane && o.vel_source != kVelocityNone)
      shift += o.vel_xy * state.td_offset_at(c);
    // Camera k's image was taken Δ_k after cam0's at the same stamp: z = h(clone) + V·(shift of cam0's t_d) + V·Δ_k.
    const int c_own = delta_col[o.cam];
    if (c_own >= 0)
      shift += o.vel_xy * state.cam_td[o.cam - 1].delta;
    const double rho = row_factor(view, obs);
    const bool readout_shift = view.readout_s != 0.0 && o.has_readout_vel;
    if (readout_shift) {
      shift += o.vel_readout * (view.readout_s * rho);
      readout_velocity(view, c, p_f, p_f_lin, o.vel_xy, true, o.vel_readout, &Jv);
    }
    Eigen::Matrix2d Jd;
    if (intr_cols) {
      // With the intrinsics in the state the measurement is the raw pixel: r = uv − π_d(k; ẑ + shift), exact in k.
      const Eigen::Vector2d zs = zhat + shift;
      out.r.segment<2>(2 * k) = obs.uv - view.cam->distort(zs, &Jd);
      out.H_x.block<2, 8>(2 * k, c_intr) = view.cam->intrinsics_jacobian(zs);
    } else {
      // Rows are scaled to distorted pixels by the distortion Jacobian at the observation, so that the tracker's
      // isotropic pixel noise is modelled where it arises: undistortion magnifies it by up to 1.5x at the EuRoC
      // image corners, which in normalised units gates most edge features. J_d is constant in the state, so the
      // rows stay exact derivatives of the (scaled) residual.
      const Eigen::Vector2d &xy = obs.xy;
      view.cam->distort(xy, &Jd);
      out.r.segment<2>(2 * k) = Jd * (xy - shift - zhat);
    }
    out.H_x.block<2, 3>(2 * k, 6 * k) = Jd * J.H_theta;
    out.H_x.block<2, 3>(2 * k, 6 * k + 3) = Jd * J.H_p;
    out.H_f.block<2, 3>(2 * k, 0) = Jd * J.H_f;
    if (o.td_column)
      out.H_x.block<2, 1>(2 * k, c_td) = Jd * o.vel_xy;
    if (c_own >= 0)
      out.H_x.block<2, 1>(2 * k, c_own) = Jd * o.vel_xy;
    o.Jd = Jd;
    if (ext_cols) {
      out.H_x.block<2, 3>(2 * k, c_ext) = Jd * J.H_ext_theta;
      out.H_x.block<2, 3>(2 * k, c_ext + 3) = Jd * J.H_ext_p;
    }
    if (readout_shift) {
      // The shift's own dependence on the state, through the velocity the state predicts (zero when tracked).
      const double tr = view.readout_s * rho;
      out.H_x.block<2, 3>(2 * k, 6 * k) += tr * Jd * Jv.H_theta;
      out.H_x.block<2, 3>(2 * k, 6 * k + 3) += tr * Jd * Jv.H_p;
      out.H_f.block<2, 3>(2 * k, 0) += tr * Jd * Jv.H_f;
      if (ext_cols) {
        out.H_x.block<2, 3>(2 * k, c_ext) += tr * Jd * Jv.H_ext_theta;
        out.H_x.block<2, 3>(2 * k, c_ext + 3) += tr * Jd * Jv.H_ext_p;
      }
    }
    if (readout_col)
      out.H_x.block<2, 1>(2 * k, c_ro) = Jd * o.vel_readout * rho;
  }
  return true;
}

bool UpdaterMSCKF::readout_velocity(const CameraView &view, const CloneState &c, const Eigen::Vector3d &p_W,
                                    const Eigen::Vector3d &p_lin_f, const Eigen::Vector2d &tracked, bool has_tracked,
                                    Eigen::Vector2d &vel, CloneMeasurementJacobians *J) const {
  if (!opt_.readout_state_velocity) {
    if (J)
      *J = CloneMeasurementJacobians::zero();
    vel = tracked;
    return has_tracked;
  }
  if (!c.has_motion || !predicted_image_velocity(c.R, c.p, view.R_BC, view.p_BC, p_W, c.motion, vel))
    return false;
  Eigen::Vector2d at_lin;
  return !J || predicted_image_velocity(c.R_lin(), c.p_lin(), view.R_BC, view.p_BC, p_lin_f, c.motion, at_lin, J);
}

UpdateStats UpdaterMSCKF::update(State &state, const std::vector<const ovton::core::Feature *> &features,
                                 TdObservation td_obs, const VelocityProvider &velocities,
                                 std::vector<ResidualRecord> *log) {
  ++update_count_;
  UpdateStats st;
  st.features_in = static_cast<int>(features.size());
  st.td_before = st.td_after = state.td;
  const int dim = state.dim();

  // Longest usable tracks first: they carry the most information when max_features cuts the list.
  std::vector<std::pair<int, const ovton::core::Feature *>> order;
  order.reserve(features.size());
  for (const ovton::core::Feature *f : features) {
    if (!f)
      throw ovton::core::UsageError("UpdaterMSCKF::update: null feature");
    usable_observations(state, *f, td_obs, usable_);
    if (static_cast<int>(usable_.size()) < opt_.min_observations) {
      ++st.too_few_observations;
      continue;
    }
    order.emplace_back(static_cast<int>(usable_.size()), f);
  }
  std::stable_sort(order.begin(), order.end(), [](const auto &a, const auto &b) {
    return a.first != b.first ? a.first > b.first : a.second->id < b.second->id;
  });
  if (opt_.max_features > 0 && static_cast<int>(order.size()) > opt_.max_features) {
    st.over_limit = static_cast<int>(order.size()) - opt_.max_features;
    order.resize(opt_.max_features);
  }

  const double sigma2 = opt_.sigma_px * opt_.sigma_px;
  size_t n_acc = 0;
  double td_bias = 0.0; // Σ_f tr(Q₂ᵀDQ₂) (td_velocity_debias)
  std::vector<Usable> usable;
  for (const auto &[count, fp] : order) {
    const ovton::core::Feature &f = *fp;
    const TriangulationResult tri = triangulate_feature(state, f, td_obs, velocities);
    if (!tri.ok() || !linearize(state, f, tri.p_W, td_obs, velocities, lin_)) {
      ++st.rejected_triangulation;
      if (tri.quality == TriangulationQuality::LowParallax || tri.quality == TriangulationQuality::IllConditioned)
        ++st.low_parallax;
      if (log) {
        usable_observations(state, f, td_obs, usable);
        append_records(state, f, nullptr, usable, td_obs, velocities, tri.p_W, ResidualRecord::kNaN,
                       ResidualRecord::kNaN, ResidualStatus::TriangulationFailed, *log);
      }
      continue;
    }
    if (n_acc == accepted_.size())
      accepted_.emplace_back();
    Accepted &a = accepted_[n_acc];
    a.cols = lin_.cols;
    const bool rig = seen_by_further_camera(lin_); // its rows repeat clone columns (merged once it is accepted)
    a.H = lin_.H_x;
    a.r = lin_.r;
    // Projected copies: lin_ keeps the pre-projection residuals that the log reports. With correlated track errors
    // the rows are whitened first, so that what is stacked has noise σ²I like every other feature's.
    const double rho = opt_.track_correlation;
    if (rho != 0.0) {
      H_f_white_ = lin_.H_f;
      whiten_track_rows(a.H, rho);
      whiten_track_rows(a.r, rho);
      whiten_track_rows(H_f_white_, rho);
    }
    qr_.compute(rho != 0.0 ? H_f_white_ : lin_.H_f); // once, for the projection and its covariance
    nullspace_project(qr_, a.H, a.r);

    // S = H P Hᵀ + σ²I over the involved columns only, from the unprojected rows' block structure.
    const Eigen::MatrixXd S = projected_innovation(lin_, qr_, state_helper::sub_covariance(state, a.cols), sigma2, rho);
    const double chi2 = a.r.dot(S.ldlt().solve(a.r));
    const int dof = static_cast<int>(a.r.size());
    const double thr = chi2_threshold(dof);
    const bool pass = std::isfinite(chi2) && chi2 < thr;
    if (log) {
      usable.clear();
      for (const auto &o : lin_.obs)
        usable.push_back({o.obs_index, o.clone, o.cam});
      append_records(state, f, &lin_, usable, td_obs, velocities, tri.p_W, chi2, thr,
                     pass ? ResidualStatus::Accepted : ResidualStatus::GatedChi2, *log);
    }
    if (!pass) {
      ++st.gated_chi2;
      continue;
    }
    if (opt_.covariance_track_correlation != 0.0) {
      // The projected rows' extra noise under the reported covariance's track model: σ²(B Bᵀ − I); a rig's feature
      // by its image times and cameras (rig_track_correlation).
      if (rig) {
        a.dR =
            sigma2 * projected_rig_track_covariance(qr_, rig_track_correlation(lin_, opt_.covariance_track_correlation,
                                                                               opt_.covariance_camera_correlation))
                         .bottomRightCorner(dof, dof);
      } else {
        const Eigen::MatrixXd B = projected_track_noise_factor(qr_, opt_.covariance_track_correlation);
        a.dR = sigma2 * (B * B.transpose());
      }
      a.dR.diagonal().array() -= sigma2;
    }
    // A rig's clone columns once each: the stacked system and G below then work on the feature's distinct columns
    // (half as many for a stereo feature; G's products were the reported covariance's dearest step).
    if (rig)
      merge_repeated_columns(a.cols, a.H);
    ++n_acc;
    ++st.features_used;
    td_bias += td_bias_to_remove(lin_, f, velocities, qr_);
    st.rows_stacked += dof;
    bool any = false;
    for (const auto &o : lin_.obs)
      if (o.td_column) {
        ++st.td_obs_used[o.vel_source];
        any = true;
      }
    st.td_features_used += any ? 1 : 0;
  }
  if (n_acc == 0)
    return st;

  // Scatter the compact blocks into one system over the union of their columns (in state order): the update never
  // forms the landmarks' and IMU's zero columns.
  cols_.clear();
  for (size_t k = 0; k < n_acc; ++k)
    cols_.insert(cols_.end(), accepted_[k].cols.begin(), accepted_[k].cols.end());
  std::sort(cols_.begin(), cols_.end());
  cols_.erase(std::unique(cols_.begin(), cols_.end()), cols_.end());
  where_.assign(static_cast<size_t>(dim), -1);
  for (size_t j = 0; j < cols_.size(); ++j)
    where_[cols_[j]] = static_cast<int>(j);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(st.rows_stacked, static_cast<Eigen::Index>(cols_.size()));
  Eigen::VectorXd r(st.rows_stacked);
  int row = 0;
  for (size_t k = 0; k < n_acc; ++k) {
    const Accepted &a = accepted_[k];
    const int rows = static_cast<int>(a.r.size());
    for (size_t j = 0; j < a.cols.size(); ++j) // distinct columns (merged above)
      H.block(row, where_[a.cols[j]], rows, 1) = a.H.col(static_cast<Eigen::Index>(j));
    r.segment(row, rows) = a.r;
    row += rows;
  }
  // The reported covariance's extra noise (covariance_track_correlation), seen through each feature's projected rows:
  // G = Σ_f H_fᵀ ΔR_f H_f — independent of the compression below.
  Eigen::MatrixXd G;
  if (opt_.covariance_track_correlation != 0.0) {
    G.setZero(static_cast<Eigen::Index>(cols_.size()), static_cast<Eigen::Index>(cols_.size()));
    for (size_t k = 0; k < n_acc; ++k) {
      const Accepted &a = accepted_[k];
      const Eigen::MatrixXd Gf = a.H.transpose() * a.dR * a.H;
      for (size_t j = 0; j < a.cols.size(); ++j)
        for (size_t i = 0; i < a.cols.size(); ++i)
          G(where_[a.cols[i]], where_[a.cols[j]]) += Gf(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
    }
  }
  compress(H, r);
  st.rows_update = static_cast<int>(r.size());
  st.mahalanobis = state_helper::ekf_update(state, cols_, H, r, sigma2, {nullptr, G.size() ? &G : nullptr});
  st.td_debias_s = remove_td_bias(state, td_bias);
  st.td_after = state.td;
  return st;
}

} // namespace ovton::msckf
