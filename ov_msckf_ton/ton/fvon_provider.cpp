#include "ov_msckf_ton/ton/fvon_provider.h"
#include "ov_core/types/errors.h"
#include "ov_msckf_ton/update/feature_jacobians.h"
#include "ov_msckf_ton/update/updater_msckf.h"

#include <algorithm>
#include <map>

namespace ovton::msckf {

namespace {

/// Later observations (after the first) that carry a tracked velocity, counted up to the first gap.
int later_velocities(const ovton::core::Feature &f) {
  int n = 0;
  for (size_t i = 1; i < f.obs.size() && f.obs[i].vel_valid; ++i)
    ++n;
  return n;
}

bool well_tracked(const ovton::core::Feature &f) {
  if (f.obs.size() < 2)
    return false;
  for (const auto &o : f.obs)
    if (!o.vel_valid)
      return false;
  return true;
}

} // namespace

FvonVelocityProvider::FvonVelocityProvider(const ovton::core::CameraCalib &calib, const FvonProviderOptions &options,
                                           bool stencils)
    : opt_(options), stencils_(stencils), R_BC_(calib.T_BC.topLeftCorner<3, 3>()),
      p_BC_(calib.T_BC.topRightCorner<3, 1>()), focal_(0.5 * (calib.intrinsics(0) + calib.intrinsics(1))),
      its_(options.its), f2f_(options.f2f) {
  if (!(focal_ > 0))
    throw ovton::core::UsageError("FvonVelocityProvider: focal lengths must be positive");
  if (opt_.max_labels < 1 || opt_.min_f2f_labels < 1 || opt_.its_min_later < 1)
    throw ovton::core::UsageError("FvonVelocityProvider: max_labels, min_f2f_labels and its_min_later must be >= 1");
  if (!(opt_.gate_px_s >= 0))
    throw ovton::core::UsageError("FvonVelocityProvider: gate_px_s must be >= 0");
}

bool FvonVelocityProvider::keep_prediction(const ovton::core::Feature &f, const Prediction &p) {
  FvonCandidates &c = candidates_[f.id];
  c.chosen = p.source;
  if (opt_.gate_px_s > 0 && f.obs.size() >= 2 && f.obs[1].vel_valid &&
      (p.vel_xy - f.obs[1].vel_xy).norm() * focal_ > opt_.gate_px_s) {
    ++stats_.gated;
    c.gated = true;
    return false;
  }
  predictions_[f.id] = p;
  return true;
}

Eigen::Vector2d FvonVelocityProvider::predict_its(const ovton::core::Feature &f, VelocityStencil *stencil) {
  const int n = later_velocities(f);
  its_seq_.clear();
  for (int i = 1; i <= n; ++i)
    its_seq_.push_back(f.obs[i].vel_xy * focal_);
  const Eigen::Vector2d v = its_.predict(its_seq_) / focal_;
  if (stencil)
    its_stencil(f, n, *stencil);
  FvonCandidates &c = candidates_[f.id];
  c.has_its = true;
  c.its = v;
  return v;
}

void FvonVelocityProvider::its_stencil(const ovton::core::Feature &f, int n, VelocityStencil &stencil) {
  // ∂prediction/∂V_i by central differences (ITS works in px/s: the focal cancels), each V_i through eq. 2's
  // stencil. The step is small against the normaliser's spread, so that it stays a derivative of the LSTM's tanh
  // units even when a flat window shrinks the spread to its 1 px/s floor.
  stencil.clear();
  const Eigen::Vector2d step = 1e-3 * its_.input_scale();
  VelocityStencil of_input;
  for (int i = 1; i <= n; ++i) {
    Eigen::Matrix2d J;
    for (int c = 0; c < 2; ++c) {
      const Eigen::Vector2d keep = its_seq_[i - 1];
      its_seq_[i - 1](c) = keep(c) + step(c);
      const Eigen::Vector2d plus = its_.predict(its_seq_);
      its_seq_[i - 1](c) = keep(c) - step(c);
      J.col(c) = (plus - its_.predict(its_seq_)) / (2 * step(c));
      its_seq_[i - 1] = keep;
    }
    VelocityProvider::stencil(f, static_cast<size_t>(i), of_input);
    stencil.add(of_input, J);
  }
}

void FvonVelocityProvider::prepare(const State &state, const std::vector<const ovton::core::Feature *> &features,
                                   const UpdaterMSCKF &updater) {
  predictions_.clear();
  candidates_.clear();
  p_W_.clear();
  updater_ = &updater;
  std::vector<const ovton::core::Feature *> need_its, need_f2f;
  for (const auto *f : features) {
    if (f->obs.empty() || f->obs.front().vel_valid)
      continue;
    (later_velocities(*f) >= opt_.its_min_later ? need_its : need_f2f).push_back(f);
  }
  if (need_its.empty() && need_f2f.empty())
    return;
  const std::vector<const ovton::core::Feature *> f2f_by_rule = need_f2f;

  std::vector<const ovton::core::Feature *> its_done;
  if (!need_its.empty()) {
    // Stage 2, ITS branch: train on the velocity sequences of the well-tracked features of this update, longest
    // first (most (V^{k+1} -> V^k) pairs per track) until the label budget is used.
    std::vector<const ovton::core::Feature *> tracks;
    for (const auto *f : features)
      if (well_tracked(*f))
        tracks.push_back(f);
    std::stable_sort(tracks.begin(), tracks.end(),
                     [](const auto *a, const auto *b) { return a->obs.size() > b->obs.size(); });
    its_.clear_tracks();
    int pairs = 0;
    for (const auto *f : tracks) {
      if (pairs >= opt_.max_labels)
        break;
      its_seq_.clear();
      for (const auto &o : f->obs)
        its_seq_.push_back(o.vel_xy * focal_);
      its_.add_track(its_seq_);
      pairs += static_cast<int>(its_seq_.size()) - 1;
    }
    if (its_.num_tracks() > 0) {
      its_.train();
      ++stats_.its_trainings;
    }
    for (const auto *f : need_its) {
      if (!its_.trained()) {
        need_f2f.push_back(f); // no well-tracked feature has been seen yet: F2F is the only option
        continue;
      }
      Prediction p;
      p.t_cam_ns = f->obs.front().t_cam_ns;
      p.vel_xy = predict_its(*f, stencils_ ? &p.stencil : nullptr);
      p.source = kVelocityItsFvon;
      ++stats_.its_predictions;
      keep_prediction(*f, p);
      its_done.push_back(f);
    }
  }
  if (evaluate_both_ && its_.trained())
    for (const auto *f : f2f_by_rule)
      if (later_velocities(*f) >= 1)
        predict_its(*f);

  if (!need_f2f.empty())
    f2f_pass(
        state, features, need_f2f, f2f_,
        [&](const ovton::core::Feature &f, const Eigen::Vector2d &v, int64_t t) {
          FvonCandidates &c = candidates_[f.id];
          c.has_f2f = true;
          c.f2f = v;
          Prediction p;
          p.t_cam_ns = t;
          p.vel_xy = v;
          p.source = kVelocityF2fFvon;
          ++stats_.f2f_predictions;
          keep_prediction(f, p);
        },
        [&](const ovton::core::Feature &) { ++stats_.no_prediction; });
  if (evaluate_both_ && !its_done.empty()) {
    // On a copy: training F2F on more frames would move the weights the filter's own predictions warm-start from.
    ton::F2fFvon shadow = f2f_;
    f2f_pass(
        state, features, its_done, shadow,
        [&](const ovton::core::Feature &f, const Eigen::Vector2d &v, int64_t) {
          FvonCandidates &c = candidates_[f.id];
          c.has_f2f = true;
          c.f2f = v;
        },
        [](const ovton::core::Feature &) {});
  }
}

void FvonVelocityProvider::f2f_pass(
    const State &state, const std::vector<const ovton::core::Feature *> &features,
    const std::vector<const ovton::core::Feature *> &need, ton::F2fFvon &net,
    const std::function<void(const ovton::core::Feature &, const Eigen::Vector2d &, int64_t)> &out,
    const std::function<void(const ovton::core::Feature &)> &none) {
  // Stage 2, F2F branch: one training per frame that holds a new feature, on the 3D positions (in that camera) and
  // tracked velocities of the other features the frame sees. Points come from the same triangulation the update
  // does, from the current clone estimates; observations are shifted by tracked velocities only.
  if (p_W_.empty())
    for (const auto *f : features) {
      const TriangulationResult tr = updater_->triangulate_feature(state, *f, TdObservation::ImagePlane, tracked_);
      if (tr.ok())
        p_W_[f->id] = tr.p_W;
    }
  std::map<int64_t, std::vector<const ovton::core::Feature *>> by_frame;
  for (const auto *f : need)
    by_frame[f->obs.front().t_cam_ns].push_back(f);

  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector2d>> labels;
  for (const auto &[t, group] : by_frame) {
    const auto clone = state.clones.find(t);
    if (clone == state.clones.end()) {
      for (const auto *f : group)
        none(*f);
      continue;
    }
    const CloneState &c = clone->second;
    const auto in_camera = [&](size_t id, Eigen::Vector3d &p_C) {
      const auto it = p_W_.find(id);
      Eigen::Vector2d z;
      return it != p_W_.end() && project_in_clone(c.R, c.p, R_BC_, p_BC_, it->second, z, &p_C);
    };
    labels.clear();
    Eigen::Vector3d p_C;
    for (const auto *g : features) {
      const ovton::core::FeatureObservation *o = g->at(t);
      if (o && o->vel_valid && in_camera(g->id, p_C))
        labels.emplace_back(p_C, o->vel_xy * focal_);
    }
    if (static_cast<int>(labels.size()) < opt_.min_f2f_labels) {
      for (const auto *f : group)
        none(*f);
      continue;
    }
    // Evenly spaced subset (features are in id order, i.e. roughly detection order): the budget bounds the cost
    // without favouring one part of the image.
    net.clear_labels();
    const size_t n = labels.size(), keep = std::min(n, static_cast<size_t>(opt_.max_labels));
    for (size_t k = 0; k < keep; ++k) {
      const auto &l = labels[k * n / keep];
      net.add_label(l.first, l.second);
    }
    net.train();
    if (&net == &f2f_)
      ++stats_.f2f_trainings;
    for (const auto *f : group) {
      if (!in_camera(f->id, p_C)) {
        none(*f);
        continue;
      }
      out(*f, net.predict(p_C) / focal_, t);
    }
  }
}

const FvonVelocityProvider::Prediction *FvonVelocityProvider::prediction_for(const ovton::core::Feature &feature,
                                                                             size_t obs_index) const {
  const auto it = predictions_.find(feature.id);
  return it != predictions_.end() && it->second.t_cam_ns == feature.obs[obs_index].t_cam_ns ? &it->second : nullptr;
}

bool FvonVelocityProvider::velocity(const ovton::core::Feature &feature, size_t obs_index, Eigen::Vector2d &vel_xy,
                                    int &source) const {
  if (feature.obs[obs_index].vel_valid)
    return tracked_for_update_->velocity(feature, obs_index, vel_xy, source);
  const Prediction *p = prediction_for(feature, obs_index);
  if (!p) {
    source = kVelocityNone;
    return false;
  }
  vel_xy = p->vel_xy;
  source = p->source;
  return true;
}

void FvonVelocityProvider::stencil(const ovton::core::Feature &feature, size_t obs_index, VelocityStencil &out) const {
  if (feature.obs[obs_index].vel_valid) {
    tracked_for_update_->stencil(feature, obs_index, out);
    return;
  }
  const Prediction *p = prediction_for(feature, obs_index);
  if (p)
    out = p->stencil;
  else
    out.clear();
}

} // namespace ovton::msckf
