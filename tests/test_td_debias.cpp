// The errors-in-variables bias of image-plane t_d rows (UpdaterMSCKFOptions::td_velocity_debias): a tracked velocity
// is a difference of the track's own noisy points, so the t_d column and the residual share noise. Checked here:
// each velocity's stencil reproduces the velocity, the predicted spurious correlation tr(Q₂ᵀDQ₂) matches a Monte
// Carlo of hᵀr over one feature's projected rows, and whole updates at the true t_d move t̂_d off it on average
// without the correction and not with it.
#include "ov_msckf_ton/update/td_observation.h"
#include "ov_msckf_ton/update/updater_msckf.h"
#include "update_test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

using namespace ov_msckf_ton;
using namespace updtest;

namespace {

/// Σ W_j·xy_j of a stencil.
Eigen::Vector2d apply(const VelocityStencil &s, const ov_core::Feature &f) {
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
  ov_core::FeatureDatabase db;
  observe(sc, db, 0.5, 4);
  const ov_core::Feature &f = *db.get(1);
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
      ov_core::FeatureDatabase db;
      observe(sc, db, sigma, 1000 + draw);
      const ov_core::Feature &f = *db.get(0);
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
      ov_core::FeatureDatabase db;
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
