// The errors-in-variables bias of image-plane t_d rows (UpdaterMSCKFOptions::td_velocity_debias): a tracked velocity
// is a difference of the track's own noisy points, so the t_d column and the residual share noise. Checked here:
// each velocity's stencil reproduces the velocity, the predicted spurious correlation tr(Q₂ᵀDQ₂) matches a Monte
// Carlo of hᵀr over one feature's projected rows, ITS-FVON's stencil is its prediction's derivative, and whole
// updates at the true t_d move t̂_d off it on average without the correction and not with it.
#include "ov_msckf_ton/ton/fvon_provider.h"
#include "ov_msckf_ton/update/td_observation.h"
#include "ov_msckf_ton/update/updater_msckf.h"
#include "update_test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

using namespace ovton::msckf;
using namespace updtest;

namespace {

/// Σ W_j·xy_j of a stencil.
Eigen::Vector2d apply(const VelocityStencil &s, const ovton::core::Feature &f) {
  Eigen::Vector2d v = Eigen::Vector2d::Zero();
  for (const auto &[i, w] : s.terms)
    v += w * f.obs[i].xy;
  return v;
}

struct MeanSe {
  double sum = 0, sum2 = 0;
  int n = 0;
  void add(double x) {
    sum += x;
    sum2 += x * x;
    ++n;
  }
  double mean() const { return sum / n; }
  double se() const { return std::sqrt((sum2 / n - mean() * mean()) / n); }
};

} // namespace

TEST(TdDebias, StencilsReproduceTheVelocities) {
  const Scene sc = make_scene(6, 3, 2.0, 0.0, 3);
  ovton::core::FeatureDatabase db;
  observe(sc, db, 0.5, 4);
  const ovton::core::Feature &f = *db.get(1);
  const VelocityProvider backward;
  const CentralVelocityProvider central;
  const NextForFirstVelocityProvider next_backward(backward), next_central(central);
  const VelocityProvider *providers[] = {&backward, &central, &next_backward, &next_central};
  VelocityStencil st;
  for (const VelocityProvider *p : providers)
    for (size_t i = 0; i < f.obs.size(); ++i) {
      Eigen::Vector2d v;
      int src = kVelocityNone;
      p->stencil(f, i, st);
      if (!p->velocity(f, i, v, src)) {
        EXPECT_TRUE(st.terms.empty()) << "no velocity, no stencil (observation " << i << ")";
        continue;
      }
      EXPECT_LT((apply(st, f) - v).norm(), 1e-9 * (1 + v.norm())) << "observation " << i;
    }
  // The central difference leaves the observation itself out; the backward one and the borrowed next one do not.
  central.stencil(f, 2, st);
  for (const auto &[i, w] : st.terms)
    EXPECT_TRUE(i != 2 || w.norm() < 1e-9) << "the central difference carries its own observation";
  next_backward.stencil(f, 0, st);
  EXPECT_EQ(st.terms.size(), 2u);
}

// hᵀr/σ² over one feature's nullspace-projected rows, linearised at the true point and poses (so r is the pixel
// noise alone): its mean over noise draws is the bias the update corrects, and td_velocity_bias predicts it.
TEST(TdDebias, PredictedSpuriousCorrelationMatchesMonteCarlo) {
  const Scene sc = make_scene(10, 1, 2.5, 0.0, 21);
  ASSERT_EQ(sc.points.size(), 1u);
  const State s = make_state(sc, 0.0, 0.002, 0.004, 0.005);
  UpdaterMSCKF up(sc.calib);
  const VelocityProvider backward;
  const CentralVelocityProvider central;
  const NextForFirstVelocityProvider next_backward(backward), next_central(central);
  const double sigma = 1.0;
  for (const VelocityProvider *vp :
       {static_cast<const VelocityProvider *>(&next_backward), static_cast<const VelocityProvider *>(&next_central)}) {
    MeanSe emp, pred;
    for (int draw = 0; draw < 3000; ++draw) {
      ovton::core::FeatureDatabase db;
      observe(sc, db, sigma, 1000 + draw);
      const ovton::core::Feature &f = *db.get(0);
      FeatureLinearization lin;
      ASSERT_TRUE(up.linearize(s, f, sc.points[0], TdObservation::ImagePlane, *vp, lin));
      const UpdaterMSCKF::FeatureQR qr(lin.H_f);
      pred.add(UpdaterMSCKF::td_velocity_bias(lin, f, *vp, qr));
      const int td_col = static_cast<int>(lin.cols.size()) - 1;
      ASSERT_EQ(lin.cols[td_col], s.td_index);
      Eigen::MatrixXd H = lin.H_x;
      Eigen::VectorXd r = lin.r;
      UpdaterMSCKF::nullspace_project(qr, H, r);
      emp.add(H.col(td_col).dot(r) / (sigma * sigma));
    }
    std::cout << "[ t_d EIV ] " << (vp == &next_backward ? "backward" : "central") << ": E[h'r]/s2 Monte Carlo "
              << emp.mean() << " +- " << emp.se() << ", predicted " << pred.mean() << " 1/s\n";
    // Backward for the newest row and the next row's backward difference for the first one: their biases add up
    // where central differences in between leave little (they cancel at the ends).
    EXPECT_TRUE(vp != &next_backward || std::abs(emp.mean()) > 5 * emp.se())
        << "the bias must be there for the test to mean anything: " << emp.mean() << " +- " << emp.se();
    EXPECT_LT(std::abs(emp.mean() - pred.mean()), 4 * emp.se());
  }
}

// Whole updates with the state at the truth (t̂_d = t_d): the mean correction of t̂_d over noise draws is the bias.
TEST(TdDebias, CorrectedUpdatesLeaveTdUnbiased) {
  const Scene sc = make_scene(10, 20, 2.5, 0.0, 31);
  ASSERT_GE(sc.points.size(), 15u);
  const CentralVelocityProvider central;
  const NextForFirstVelocityProvider vp(central);
  for (bool debias : {false, true}) {
    UpdaterMSCKFOptions o;
    o.td_velocity_debias = debias ? 1.0 : 0.0;
    UpdaterMSCKF up(sc.calib, o);
    MeanSe dtd;
    double sigma_after = 0.0;
    for (int draw = 0; draw < 300; ++draw) {
      ovton::core::FeatureDatabase db;
      observe(sc, db, 1.0, 5000 + draw);
      State s = make_state(sc, 0.0, 0.002, 0.004, 0.005);
      const UpdateStats st = up.update(s, all_features(db), TdObservation::ImagePlane, vp);
      ASSERT_GT(st.td_features_used, 10);
      EXPECT_EQ(st.td_debias_s != 0.0, debias);
      dtd.add(s.td);
      sigma_after = s.td_sigma();
    }
    std::cout << "[ t_d EIV ] updates at the true t_d, debias " << debias << ": mean t_d " << dtd.mean() * 1e3 << " +- "
              << dtd.se() * 1e3 << " ms (posterior sigma " << sigma_after * 1e3 << " ms)\n";
    if (debias) {
      EXPECT_LT(std::abs(dtd.mean()), 3 * dtd.se());
    } else {
      EXPECT_GT(dtd.mean(), 5 * dtd.se()) << "eq. 2's shared noise pushes t_d ahead";
    }
  }
}

// ITS-FVON predicts a new track's first velocity from its later (eq. 2) velocities: the stencil it hands the update
// must be the prediction's derivative with respect to the track's points.
TEST(TdDebias, ItsPredictionStencilIsItsDerivative) {
  const Scene sc = make_scene(12, 40, 2.5, 0.0, 41);
  ASSERT_GE(sc.points.size(), 30u);
  ovton::core::FeatureDatabase db;
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, 0.3);
  // Points 0-19 seen throughout (their first observations dropped below, so they are "well tracked": ITS's
  // labels); points 20-29 new from image 6 on (first observation without a velocity, five later ones).
  for (size_t k = 0; k < sc.stamps.size(); ++k) {
    const Pose P = sc.pose_at(sc.t_of(sc.stamps[k]));
    for (size_t id = 0; id < 30; ++id) {
      if (id >= 20 && k < 6)
        continue;
      Eigen::Vector2d xy;
      ASSERT_TRUE(sc.project(P, sc.points[id], xy));
      const Eigen::Vector2d uv = sc.cam.distort(xy) + Eigen::Vector2d(n(rng), n(rng));
      db.add_observation(id, sc.stamps[k], uv, sc.cam.undistort(uv));
    }
  }
  db.remove_observations_older_than(sc.stamps[2]);
  FvonProviderOptions o;
  o.gate_px_s = 0; // the derivative is checked whatever the prediction's quality
  o.its.train.max_epochs = 300;
  FvonVelocityProvider fvon(sc.calib, o, /*stencils=*/true);
  UpdaterMSCKF up(sc.calib);
  const State s = make_state(sc, 0.0, 0.002, 0.004, 0.005);
  fvon.prepare(s, all_features(db), up);
  const double focal = 0.5 * (sc.calib.intrinsics(0) + sc.calib.intrinsics(1));
  int checked = 0;
  for (size_t id = 20; id < 30; ++id) {
    const ovton::core::Feature &f = *db.get(id);
    Eigen::Vector2d v;
    int src = kVelocityNone;
    if (!fvon.velocity(f, 0, v, src) || src != kVelocityItsFvon)
      continue; // gated
    VelocityStencil st;
    fvon.stencil(f, 0, st);
    ASSERT_EQ(st.terms.size(), f.obs.size()) << "every point from the first to the last later velocity";
    // ITS's prediction from the track with point j moved by h along axis c, velocities recomputed by eq. 2.
    const auto predict = [&](size_t j, int c, double h) {
      std::vector<Eigen::Vector2d> seq;
      for (size_t i = 1; i < f.obs.size(); ++i) {
        Eigen::Vector2d a = f.obs[i].xy, b = f.obs[i - 1].xy;
        a(c) += i == j ? h : 0.0;
        b(c) += i - 1 == j ? h : 0.0;
        seq.push_back((a - b) / (1e-9 * static_cast<double>(f.obs[i].t_cam_ns - f.obs[i - 1].t_cam_ns)) * focal);
      }
      return Eigen::Vector2d(fvon.its().predict(seq) / focal);
    };
    EXPECT_LT((predict(0, 0, 0.0) - v).norm(), 1e-9 * (1 + v.norm())) << "the same prediction as the provider's";
    const double h = 1e-6;
    for (const auto &[j, W] : st.terms)
      for (int c = 0; c < 2; ++c) {
        const Eigen::Vector2d num = (predict(j, c, h) - predict(j, c, -h)) / (2 * h);
        EXPECT_LT((num - W.col(c)).norm(), 1e-3 * (1 + W.col(c).norm())) << "feature " << id << ", point " << j;
      }
    ++checked;
  }
  EXPECT_GT(checked, 3) << "too few ITS predictions to check: ITS trainings " << fvon.stats().its_trainings
                        << ", predictions " << fvon.stats().its_predictions << ", gated " << fvon.stats().gated
                        << ", F2F " << fvon.stats().f2f_predictions;
}
