#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_core/math/so3.h"
#include "ov_core/types/errors.h"
#include "ov_core/types/state_interpolation.h"
#include "ov_msckf_ton/state/state_helper.h"

#include <algorithm>
#include <chrono>
#include <optional>

namespace ovton::msckf {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

ImuNoise noise_from(const ovton::core::ImuCalib &imu, const VioOptions &opt) {
  ImuNoise n;
  const double k = opt.imu.noise_multiplier;
  const auto pick = [k](double configured, double folder) { return k * (configured > 0 ? configured : folder); };
  n.sigma_w = pick(opt.imu.gyroscope_noise_density, imu.gyro_noise_density);
  n.sigma_a = pick(opt.imu.accelerometer_noise_density, imu.accel_noise_density);
  n.sigma_wb = pick(opt.imu.gyroscope_random_walk, imu.gyro_random_walk);
  n.sigma_ab = pick(opt.imu.accelerometer_random_walk, imu.accel_random_walk);
  return n;
}

TdObservation td_observation(TdMode m) {
  if (uses_state_relevant(m))
    return TdObservation::StateRelevant;
  if (uses_sir(m))
    return TdObservation::ImagePlane;
  return TdObservation::None;
}

} // namespace

VioManager::VioManager(const VioOptions &opt, const ovton::core::CameraCalib &cam, const ovton::core::ImuCalib &imu,
                       FilterAids aids, StateCallback on_state, std::vector<std::shared_ptr<FilterObserver>> observers,
                       std::vector<ovton::core::CameraCalib> more_cameras)
    : opt_(opt), camera_(cam), propagator_(noise_from(imu, opt), opt.imu.gravity_mag),
      updater_(cam, opt.update.msckf, std::move(more_cameras)), slam_(cam, opt.slam.updater, updater_),
      state_(std::make_unique<State>(estimates_td(opt.td.mode))), aids_(std::move(aids)),
      on_state_(std::move(on_state)), observers_(std::move(observers)), health_(opt) {
  validate_vio_options(opt_);
  for (const auto &o : observers_) {
    if (!o)
      throw ovton::core::UsageError("VioManager: a null observer");
    want_velocities_ = want_velocities_ || o->wants_velocities();
  }
  // Residual records feed the residual log and each image's feature fates.
  want_records_ = want_frames_ = !observers_.empty();
  state_->td = opt.td.init_s;
  // The calibration as the filter holds it; a variable (and a column in the updates) only where it is estimated.
  CalibState &c = state_->calib;
  c.R_BC = cam.T_BC.topLeftCorner<3, 3>();
  c.p_BC = cam.T_BC.topRightCorner<3, 1>();
  c.intrinsics << cam.intrinsics, cam.dist_coeffs;
  c.readout_s = opt.calibration.readout_s;
  if (opt.init.mode != InitMode::GroundTruth)
    inertial_init_ =
        std::make_unique<InertialInitializer>(opt.init, opt.update.msckf.sigma_px, cam.T_BC,
                                              0.5 * (cam.intrinsics(0) + cam.intrinsics(1)), opt.imu.gravity_mag);
  if (uses_fvon(opt.td.mode)) {
    fvon_ = std::make_unique<FvonVelocityProvider>(cam, opt.ton.fvon, opt.update.msckf.td_velocity_debias != 0.0);
    fvon_->set_evaluate_both(want_velocities_);
  }
  if (opt.init.mode == InitMode::GroundTruth && aids_.groundtruth.empty())
    throw ovton::core::UsageError("ground-truth initialisation needs the recording's ground truth");
  td_model_ = make_td_model(opt_, aids_.td_truth);
}

const TpnDriver *VioManager::tpn() const {
  return tpn_driver_of(*td_model_);
}

void VioManager::show_velocities(const std::vector<const ovton::core::Feature *> &feats, const VelocityProvider &used) {
  const double focal = 0.5 * (camera_.calib().intrinsics(0) + camera_.calib().intrinsics(1));
  std::vector<ovton::core::VelocityLogRow> rows;
  for (const auto *f : feats) {
    const FvonCandidates *cand = nullptr;
    if (fvon_) {
      const auto it = fvon_->candidates().find(f->id);
      cand = it == fvon_->candidates().end() ? nullptr : &it->second;
    }
    for (size_t i = 0; i < f->obs.size(); ++i) {
      const ovton::core::FeatureObservation &o = f->obs[i];
      ovton::core::VelocityLogRow r;
      r.t_cam_ns = o.t_cam_ns;
      r.feature_id = f->id;
      r.obs_index = static_cast<int>(i);
      r.track_length = static_cast<int>(f->obs.size());
      r.u_px = o.uv.x();
      r.v_px = o.uv.y();
      r.x_norm = o.xy.x();
      r.y_norm = o.xy.y();
      r.focal_px = focal;
      const auto set = [focal](double &x, double &y, const Eigen::Vector2d &v) {
        x = v.x() * focal;
        y = v.y() * focal;
      };
      if (o.vel_valid)
        set(r.eq2_x, r.eq2_y, o.vel_xy);
      if (i + 1 < f->obs.size() && f->obs[i + 1].vel_valid)
        set(r.next_x, r.next_y, f->obs[i + 1].vel_xy);
      if (i == 0 && cand) {
        if (cand->has_its)
          set(r.its_x, r.its_y, cand->its);
        if (cand->has_f2f)
          set(r.f2f_x, r.f2f_y, cand->f2f);
        r.fvon_source = cand->chosen;
        r.gated = cand->gated ? 1 : 0;
      }
      Eigen::Vector2d v;
      int src = kVelocityNone;
      r.used_source = used.velocity(*f, i, v, src) ? src : kVelocityNone;
      rows.push_back(r);
    }
  }
  for (const auto &o : observers_)
    if (o->wants_velocities())
      o->on_velocities(rows);
}

double VioManager::td_for_image_s(int64_t t_cam_ns) const {
  // The replay feeds IMU readings up to this time: it must be where the propagation will go, the model's motion
  // of t_d included.
  return td_model_->td_at_image(*state_, t_cam_ns, initialized_ ? last_image_ns_ : -1);
}

void VioManager::on_imu(const ovton::core::ImuData &m) {
  propagator_.feed_imu(m);
  if (!initialized_) {
    init_imu_.push_back(m);
    while (init_imu_.size() > 2 &&
           init_imu_.back().t_imu_ns - init_imu_.front().t_imu_ns >
               ovton::core::s_to_ns(std::max(opt_.init.window_s, opt_.init.dynamic.window_s) + 1.0))
      init_imu_.pop_front();
  }
}

InitFrame VioManager::init_frame(int64_t t_cam_ns, int64_t t_imu_ns) const {
  InitFrame f;
  f.t_cam_ns = t_cam_ns;
  f.t_imu_ns = t_imu_ns;
  std::vector<const ovton::core::Feature *> seen;
  db_.features_observed_at(t_cam_ns, seen);
  for (const auto *feat : seen)
    if (const auto *o = feat->at(t_cam_ns))
      f.obs.emplace_back(feat->id, o->xy);
  return f;
}

bool VioManager::try_initialize(int64_t t_cam_ns) {
  const int64_t t_imu = t_cam_ns + ovton::core::s_to_ns(td_for_image_s(t_cam_ns));
  State &s = *state_;
  const InitOptions &io = opt_.init;
  std::optional<Eigen::Matrix<double, ImuState::kSize, ImuState::kSize>> P_imu; // a dynamic initialisation's own
  if (io.mode == InitMode::GroundTruth) {
    ovton::core::StateSample g;
    if (!ovton::core::interpolate_state(aids_.groundtruth, t_imu, g)) {
      init_msg_ = "no ground truth at the first image";
      return false;
    }
    s.imu.R = g.q_WB.toRotationMatrix();
    s.imu.p = g.p;
    s.imu.v = g.v;
    s.imu.bg = g.bg;
    s.imu.ba = g.ba;
    init_msg_ = "initialised from ground truth";
  } else {
    std::optional<InitSolution> r = inertial_init_->try_initialize(init_frame(t_cam_ns, t_imu), init_imu_);
    if (!r) {
      init_msg_ = inertial_init_->why();
      return false;
    }
    s.imu.R = r->R_WB;
    s.imu.p = r->p;
    s.imu.v = r->v;
    s.imu.bg = r->bg;
    s.imu.ba = r->ba;
    P_imu = r->P;
    init_msg_ = r->message;
  }
  s.t_imu_ns = t_imu;
  s.imu.set_fej();
  s.P.setZero();
  const auto sq = [](double x) { return x * x; };
  s.P.diagonal().segment<2>(ImuState::kTheta).setConstant(sq(io.sigma_rollpitch));
  s.P(ImuState::kTheta + 2, ImuState::kTheta + 2) = sq(io.sigma_yaw);
  s.P.diagonal().segment<3>(ImuState::kPos).setConstant(sq(io.sigma_pos));
  s.P.diagonal().segment<3>(ImuState::kVel).setConstant(sq(io.sigma_vel));
  s.P.diagonal().segment<3>(ImuState::kBg).setConstant(sq(io.sigma_bg));
  s.P.diagonal().segment<3>(ImuState::kBa).setConstant(sq(io.sigma_ba));
  if (P_imu)
    s.P.topLeftCorner<ImuState::kSize, ImuState::kSize>() = *P_imu;
  if (s.estimates_td()) {
    s.P(s.td_index, s.td_index) = sq(opt_.td.sigma_init_s);
    td_model_->initialize(s);
    // A further camera's own offset, and its rate when asked for (a clock drifting against cam0's).
    const bool rates = opt_.td.per_camera_rate;
    const auto prior = [&](double sigma) { return Eigen::MatrixXd::Constant(1, 1, sq(sigma)); };
    for (int cam = 1; opt_.td.per_camera && cam < updater_.num_cameras(); ++cam) {
      CameraTdState c;
      c.index = s.add_variable(prior(opt_.td.per_camera_sigma_init_s));
      c.rate_index = rates ? s.add_variable(prior(opt_.td.rate_sigma_init)) : -1;
      s.cam_td.push_back(c);
    }
  }
  add_calibration_variables();
  // A track-error model for the reported covariance: from here on P_report follows P's gains (State::P_report).
  if (opt_.update.msckf.covariance_track_correlation > 0 || opt_.slam.updater.covariance_sigma_px > 0)
    s.start_report();
  initialized_ = true;
  init_imu_.clear();
  return true;
}

void VioManager::add_calibration_variables() {
  State &s = *state_;
  const CalibrationOptions &o = opt_.calibration;
  const auto add = [&](const Eigen::VectorXd &sigmas) {
    return s.add_variable(Eigen::MatrixXd(sigmas.array().square().matrix().asDiagonal()));
  };
  if (o.extrinsics) {
    Eigen::VectorXd sig(6);
    sig << Eigen::Vector3d::Constant(o.sigma_ext_rot), Eigen::Vector3d::Constant(o.sigma_ext_pos);
    s.calib.extrinsics_index = add(sig);
  }
  if (o.intrinsics) {
    Eigen::VectorXd sig(8);
    sig << o.sigma_focal_px, o.sigma_focal_px, o.sigma_center_px, o.sigma_center_px,
        Eigen::Vector4d::Constant(o.sigma_distortion);
    s.calib.intrinsics_index = add(sig);
  }
  if (o.readout)
    s.calib.readout_index = add(Eigen::VectorXd::Constant(1, o.sigma_readout_s));
  if (o.imu_intrinsics)
    s.calib.imu_intrinsics_index = add(Eigen::VectorXd::Constant(12, o.sigma_imu_intrinsics));
}

void VioManager::process_frame(int64_t t_cam_ns, const std::vector<ovton::core::TrackedFeature> &features,
                               const std::vector<std::vector<ovton::core::TrackedFeature>> &more) {
  const auto t_start = Clock::now();
  db_.add_frame(t_cam_ns, features);
  for (size_t k = 0; k < more.size(); ++k)
    db_.add_frame(t_cam_ns, more[k], static_cast<int>(k + 1));
  fate_.clear();
  ++counters_.images;
  auto t0 = Clock::now();

  State &s = *state_;
  if (!initialized_ && !try_initialize(t_cam_ns)) {
    ++counters_.images_before_init;
    // Nothing to estimate yet: keep the tracks short so the first update only sees stamps that get clones.
    db_.remove_observations_older_than(t_cam_ns);
    return;
  }

  // Propagate to the image's IMU-clock time and clone there.
  t0 = Clock::now();
  propagate_to_image(t_cam_ns);
  if (opt_.zupt.enabled && is_still(t_cam_ns)) {
    // Still images: no parallax for triangulation. Either the platform stands still (constrain the velocity instead
    // and keep no clone), or the velocity the IMU carried the state to says it moves: a frozen or re-sent frame,
    // whose observations would tie two different poses to the same pixels; the frame is dropped.
    if (zero_velocity_agrees()) {
      Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3, s.dim());
      H.block<3, 3>(0, ImuState::kVel).setIdentity();
      td_tracked_update([&] { state_helper::ekf_update(s, H, -s.imu.v, opt_.zupt.sigma_v * opt_.zupt.sigma_v); });
      ++counters_.zupts;
    } else {
      ++counters_.frozen_frames;
    }
    db_.remove_observations_at(t_cam_ns);
    times_.propagation += ms_since(t0);
    finish_image(t_cam_ns);
    ++times_.frames;
    times_.total += ms_since(t_start);
    hand_out(t_cam_ns, features);
    return;
  }
  // The clone's t_d Jacobian needs the body rate AT the image time (interpolated reading), not the mean over the
  // last IMU interval, and not a stale value: the first clone after initialisation has no interval behind it.
  ovton::core::ImuData at_image;
  const bool have_reading = propagator_.imu().interpolate(s.t_imu_ns, at_image);
  // The clone's error from a t_d error follows the TRUE body rate; a vibrating gyro's reading at one instant is not
  // it, and on a flight whose rate barely changes the filter takes the vibration for information about t_d
  // (docs/robustness.md, "Weak excitation"). A centred mean over the window removes the vibration without lag; the
  // replay hands over its second half before the image (imu_lookahead_ns).
  const int64_t half = imu_lookahead_ns();
  Eigen::Vector3d w_B, w_mean;
  if (half > 0 && propagator_.imu().mean_gyro_readings(s.t_imu_ns - half, s.t_imu_ns + half, w_mean))
    w_B = w_mean - s.imu.bg;
  else
    w_B = have_reading ? Eigen::Vector3d(at_image.wm - s.imu.bg) : propagator_.last_w_B();
  if (s.calib.imu_intrinsics_index >= 0 && have_reading)
    w_B = s.calib.D_w * w_B; // the gyro's scale and misalignment, as the propagation applies them
  state_helper::clone(s, t_cam_ns, uses_state_relevant(opt_.td.mode), w_B, s.imu.v);
  s.clones.at(t_cam_ns).has_fej = opt_.update.measurement_fej;
  times_.propagation += ms_since(t0);

  t0 = Clock::now();
  const double networks_before = times_.networks;
  update_and_marginalize(t_cam_ns);
  times_.update += ms_since(t0) - (times_.networks - networks_before);
  finish_image(t_cam_ns);

  ++times_.frames;
  times_.total += ms_since(t_start);
  hand_out(t_cam_ns, features);
}

void VioManager::hand_out(int64_t t_cam_ns, const std::vector<ovton::core::TrackedFeature> &features) {
  const ovton::core::StateSample state = snapshot(); // checks the filter's health first
  if (want_frames_) {
    FrameFeatures f;
    f.t_cam_ns = t_cam_ns;
    f.t_imu_ns = state.t_ns;
    for (const auto &tf : features) {
      f.ids.push_back(tf.id);
      f.uv.push_back(tf.uv);
      const auto it = fate_.find(tf.id);
      f.fate.push_back(it == fate_.end() ? FrameFeatures::Tracked : it->second);
    }
    for (const auto &o : observers_)
      o->on_frame(f);
  }
  for (const auto &o : observers_)
    o->on_filter(*this);
  if (on_state_)
    on_state_(state);
}

void VioManager::propagate_to_image(int64_t t_cam_ns) {
  State &s = *state_;
  const double td_end = td_model_->td_at_image(s, t_cam_ns, last_image_ns_);
  // The clone is placed at t_cam + td_end so that its td_ref agrees with where the mean will be.
  const int64_t t_imu = std::max(s.t_imu_ns, t_cam_ns + ovton::core::s_to_ns(td_end));
  const double dt_imu = ovton::core::ns_to_s(t_imu - s.t_imu_ns);
  if (!propagator_.propagate(s, t_imu))
    throw ovton::core::UsageError("IMU data does not reach image " + std::to_string(t_cam_ns));
  td_model_->propagate(s, td_end, dt_imu);
  for (CameraTdState &c : s.cam_td) {
    c.delta += c.rate * dt_imu;
    propagate_offset_covariance(s, c.index, c.rate_index, opt_.td.per_camera_random_walk, opt_.td.rate_random_walk,
                                dt_imu);
  }
}

template <typename UpdateFn> void VioManager::td_tracked_update(UpdateFn &&fn) {
  const double td0 = state_->td, v0 = state_->td_variance();
  fn();
  td_model_->after_update(td0, v0, state_->td, state_->td_variance());
  health_.on_td_update(state_->t_imu_ns, td0, v0, state_->td, state_->td_variance());
}

void VioManager::finish_image(int64_t t_cam_ns) {
  last_image_ns_ = t_cam_ns;
  const auto t0 = Clock::now();
  td_model_->after_image(*state_, t_cam_ns);
  if (td_model_->kind() == TdProcess::Tpn) // TPN's training is network time; the other models' bookkeeping is not
    times_.networks += ms_since(t0);
}

bool VioManager::is_still(int64_t t_cam_ns) const {
  std::vector<const ovton::core::Feature *> seen;
  db_.features_observed_at(t_cam_ns, seen);
  std::vector<double> disparity;
  disparity.reserve(seen.size());
  for (const auto *f : seen) {
    const auto &o = f->newest();
    if (o.t_cam_ns == t_cam_ns && o.vel_valid && f->obs.size() >= 2) {
      const auto &prev = f->obs[f->obs.size() - 2];
      disparity.push_back((o.uv - prev.uv).norm());
    }
  }
  if (disparity.size() < 10)
    return false;
  std::nth_element(disparity.begin(), disparity.begin() + disparity.size() / 2, disparity.end());
  return disparity[disparity.size() / 2] < opt_.zupt.max_disparity_px;
}

bool VioManager::zero_velocity_agrees() const {
  const State &s = *state_;
  Eigen::Matrix3d S = s.P.block<3, 3>(ImuState::kVel, ImuState::kVel);
  S.diagonal().array() += opt_.zupt.sigma_v * opt_.zupt.sigma_v;
  return s.imu.v.dot(S.ldlt().solve(s.imu.v)) <= updater_.chi2_threshold(3);
}

const VelocityProvider &VioManager::prepare_velocities(const std::vector<const ovton::core::Feature *> &feats,
                                                       std::optional<NextForFirstVelocityProvider> &with_first) {
  const VelocityProvider *velocities = opt_.td.sir_velocity == SirVelocity::Central
                                           ? static_cast<const VelocityProvider *>(&central_velocities_)
                                           : &tracked_velocities_;
  if (fvon_) {
    fvon_->set_tracked(velocities);
    const auto t0 = Clock::now();
    fvon_->prepare(*state_, feats, updater_);
    velocities = fvon_.get();
    times_.networks += ms_since(t0);
  }
  // Last, so that with FVON it covers the first observations the networks could not predict (too few labels yet).
  if (opt_.td.first_velocity != FirstVelocity::Next)
    return *velocities;
  with_first.emplace(*velocities);
  return *with_first;
}

void VioManager::update_and_marginalize(int64_t t_cam_ns) {
  State &s = *state_;
  // Features the tracker lost in this frame have complete tracks; when the window is full, features seen by the
  // oldest clone must be used now or their information about it is lost — unless they are still tracked and there
  // is room for SLAM features: then they become landmarks in the state instead (delayed initialisation below).
  std::vector<const ovton::core::Feature *> feats, slam_init;
  db_.lost_features(t_cam_ns, feats);
  const bool window_full = static_cast<int>(s.clones.size()) > opt_.update.max_clones;
  int64_t oldest = s.clones.begin()->first;
  if (window_full) {
    std::vector<const ovton::core::Feature *> old;
    db_.features_observed_at(oldest, old);
    int room = std::min(opt_.slam.max_features - static_cast<int>(s.landmarks.size()), opt_.slam.max_init_per_frame);
    for (const auto *f : old) {
      if (room > 0 && f->newest().t_cam_ns == t_cam_ns && !s.landmarks.count(f->id)) {
        slam_init.push_back(f);
        --room;
      } else {
        feats.push_back(f);
      }
    }
    std::sort(feats.begin(), feats.end(), [](const auto *a, const auto *b) { return a->id < b->id; });
    feats.erase(std::unique(feats.begin(), feats.end()), feats.end());
  }
  // A landmark's observations are its own: the MSCKF never sees them.
  feats.erase(std::remove_if(feats.begin(), feats.end(), [&](const auto *f) { return s.landmarks.count(f->id) > 0; }),
              feats.end());
  std::optional<NextForFirstVelocityProvider> with_first;
  const bool any_slam = !s.landmarks.empty() || !slam_init.empty();
  if (!feats.empty() || any_slam) {
    const VelocityProvider &velocities = prepare_velocities(feats, with_first);
    if (!feats.empty())
      msckf_update(feats, velocities);
    if (any_slam)
      slam_update(t_cam_ns, slam_init, velocities);
  }
  if (window_full) {
    state_helper::marginalize_clone(s, oldest);
    db_.remove_observations_older_than(s.clones.begin()->first);
  }
}

void VioManager::msckf_update(const std::vector<const ovton::core::Feature *> &feats,
                              const VelocityProvider &velocities) {
  State &s = *state_;
  std::vector<ResidualRecord> records;
  if (want_velocities_)
    show_velocities(feats, velocities);
  UpdateStats st;
  td_tracked_update([&] {
    st = updater_.update(s, feats, td_observation(opt_.td.mode), velocities, want_records_ ? &records : nullptr);
  });
  ++counters_.updates;
  health_.on_update(s.t_imu_ns, st);
  counters_.features_used += st.features_used;
  counters_.features_gated += st.gated_chi2;
  counters_.features_rejected += st.rejected_triangulation;
  for (int k = 0; k < kNumVelocitySources; ++k) {
    counters_.td_rows += st.td_obs_used[k];
    counters_.td_rows_by_source[k] += st.td_obs_used[k];
  }
  counters_.td_features += st.td_features_used;
  if (want_records_) {
    for (const auto &o : observers_)
      o->on_residuals(records, s);
    for (const auto &r : records)
      fate_[r.feature_id] = r.status == ResidualStatus::Accepted ? FrameFeatures::Used : FrameFeatures::Gated;
  }
  // A feature used in an update must not be used again: its information is in the state now.
  std::vector<size_t> ids;
  ids.reserve(feats.size());
  for (const auto *f : feats)
    ids.push_back(f->id);
  for (size_t id : ids)
    db_.remove(id);
}

void VioManager::slam_update(int64_t t_cam_ns, const std::vector<const ovton::core::Feature *> &init,
                             const VelocityProvider &velocities) {
  State &s = *state_;
  const TdObservation td_obs = td_observation(opt_.td.mode);
  SlamStats st;
  // OpenVINS' order: existing landmarks with this image's observation, then new ones from the window.
  std::vector<size_t> lost;
  // The body's motion at this image: the rate its clone was placed with and the state's velocity (this image's clone
  // is the newest, and the state is at its time).
  const auto clone = s.clones.find(t_cam_ns);
  const std::optional<BodyMotion> motion =
      clone != s.clones.end() && clone->second.has_motion
          ? std::optional<BodyMotion>(BodyMotion{clone->second.motion.w_B, s.imu.v})
          : std::nullopt;
  td_tracked_update([&] { slam_.update(s, db_, t_cam_ns, td_obs, velocities, st, lost, motion ? &*motion : nullptr); });
  if (!init.empty())
    td_tracked_update([&] { slam_.initialize(s, init, t_cam_ns, td_obs, velocities, st); });
  // Landmarks the tracker lost in this image (or that left the camera's depth range) leave the state.
  for (const auto &[id, l] : s.landmarks) {
    const ovton::core::Feature *f = db_.get(id);
    if (!f || f->newest().t_cam_ns != t_cam_ns)
      lost.push_back(id);
  }
  std::sort(lost.begin(), lost.end());
  lost.erase(std::unique(lost.begin(), lost.end()), lost.end());
  for (size_t id : lost) {
    state_helper::marginalize_landmark(s, id);
    db_.remove(id);
  }
  st.marginalised = static_cast<int>(lost.size());
  counters_.slam_initialised += st.initialised;
  counters_.slam_updates += st.updated;
  counters_.slam_gated += st.gated;
}

ovton::core::StateSample VioManager::snapshot() const {
  const State &s = *state_;
  health_.check(s); // no row leaves the filter without it: a diverged estimate is an error, not an answer
  ovton::core::StateSample o;
  o.t_ns = s.t_imu_ns;
  o.p = s.imu.p;
  o.q_WB = Eigen::Quaterniond(s.imu.R).normalized();
  o.v = s.imu.v;
  o.bg = s.imu.bg;
  o.ba = s.imu.ba;
  o.td_s = s.td;
  // The sigmas a user sees are the reported covariance's (the filter's own P unless a track-error model is set).
  o.td_sigma_s = s.reported_td_sigma();
  for (int cam = 1; s.has_camera_td(cam); ++cam) {
    o.cam_td_s.push_back(s.td_of_camera(cam));
    o.cam_td_sigma_s.push_back(s.reported_td_sigma_of_camera(cam));
  }
  o.has_velocity = true;
  o.has_td = true;
  const auto block = [&](int r, int c) { return s.reported_block(r, c, 3, 3); };
  o.P_pose.topLeftCorner<3, 3>() = block(ImuState::kTheta, ImuState::kTheta);
  o.P_pose.topRightCorner<3, 3>() = block(ImuState::kTheta, ImuState::kPos);
  o.P_pose.bottomLeftCorner<3, 3>() = block(ImuState::kPos, ImuState::kTheta);
  o.P_pose.bottomRightCorner<3, 3>() = block(ImuState::kPos, ImuState::kPos);
  o.has_pose_cov = true;
  return o;
}

} // namespace ovton::msckf
