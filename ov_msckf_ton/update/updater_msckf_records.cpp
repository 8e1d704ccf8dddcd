// The residual log's rows of an MSCKF update (UpdaterMSCKF::append_records): every camera's observations of a feature,
// each in its own camera's geometry, with what could explain them (residual_log.h).
#include "ov_msckf_ton/update/feature_jacobians.h"
#include "ov_msckf_ton/update/updater_msckf.h"

namespace ovton::msckf {

void UpdaterMSCKF::append_records(const State &state, const ovton::core::Feature &feature,
                                  const FeatureLinearization *lin, const std::vector<Usable> &usable,
                                  TdObservation td_obs, const VelocityProvider &velocities, const Eigen::Vector3d &p_f,
                                  double chi2, double threshold, ResidualStatus status,
                                  std::vector<ResidualRecord> &log) const {
  for (size_t k = 0; k < usable.size(); ++k) {
    // Every camera's rows, each in its own geometry (a further camera's go to a file of their own: residual_log.h).
    const int cam = usable[k].cam;
    const ovton::core::Feature &track = cam == 0 ? feature : feature.more[static_cast<size_t>(cam - 1)];
    const ovton::core::CameraModel &model = cam == 0 ? camera_ : more_cam_[static_cast<size_t>(cam - 1)];
    const ovton::core::CameraCalib &calib = cam == 0 ? calib_ : more_calib_[static_cast<size_t>(cam - 1)];
    const auto jd = [&](const Eigen::Vector2d &xy) { // pixels per normalised unit at xy, in this camera
      Eigen::Matrix2d J;
      model.distort(xy, &J);
      return J;
    };
    const size_t i = usable[k].obs_index;
    const CloneState &c = *usable[k].clone;
    const ovton::core::FeatureObservation &o = track.obs[i];
    ResidualRecord rec;
    rec.cam = cam;
    rec.update_id = update_count_;
    rec.t_cam_ns = o.t_cam_ns;
    rec.feature_id = feature.id;
    rec.obs_index = static_cast<int>(i);
    rec.track_length = static_cast<int>(track.obs.size());
    rec.u_px = o.uv.x();
    rec.v_px = o.uv.y();
    rec.x_norm = o.xy.x();
    rec.y_norm = o.xy.y();
    rec.radius_norm = o.xy.norm();
    rec.td_s = state.td_of_camera(cam);
    rec.td_ref_s = c.td_ref;
    rec.chi2 = chi2;
    rec.chi2_threshold = threshold;
    rec.status = status;
    rec.accepted = status == ResidualStatus::Accepted ? 1 : 0;
    Eigen::Vector2d vel = Eigen::Vector2d::Zero();
    int src = kVelocityNone;
    if (lin) {
      vel = lin->obs[k].vel_xy;
      src = lin->obs[k].vel_source;
      rec.td_column = lin->obs[k].td_column ? 1 : 0;
      rec.depth_m = lin->obs[k].depth;
      rec.res_u_px = lin->r(2 * k); // rows are already in distorted pixels
      rec.res_v_px = lin->r(2 * k + 1);
    } else {
      if (!velocity_of(velocities, feature, usable[k], vel, src)) {
        vel.setZero();
        src = kVelocityNone;
      }
      // A rejected point can still say how wrong it was, when it is in front of the camera.
      Eigen::Vector2d zhat;
      Eigen::Vector3d p_C;
      const Eigen::Matrix3d R_BC = calib.T_BC.topLeftCorner<3, 3>();
      const Eigen::Vector3d p_BC = calib.T_BC.topRightCorner<3, 1>();
      if (p_f.allFinite() && project_in_clone(c.R, c.p, R_BC, p_BC, p_f, zhat, &p_C)) {
        Eigen::Vector2d z = o.xy;
        if (td_obs == TdObservation::ImagePlane && src != kVelocityNone)
          z -= vel * state.td_offset_at(c);
        rec.depth_m = p_C.z();
        const Eigen::Vector2d r_px = jd(o.xy) * (z - zhat);
        rec.res_u_px = r_px.x();
        rec.res_v_px = r_px.y();
      }
    }
    const Eigen::Vector2d vel_px = jd(o.xy) * vel;
    rec.vel_u_px_s = vel_px.x();
    rec.vel_v_px_s = vel_px.y();
    rec.vel_source = src;
    if (c.has_motion) {
      rec.w_x = c.motion.w_B.x();
      rec.w_y = c.motion.w_B.y();
      rec.w_z = c.motion.w_B.z();
      rec.w_valid = 1;
    }
    log.push_back(rec);
  }
}

} // namespace ovton::msckf
