// Scoring a front end's tracks against the ground truth (ov_eval/track_truth.h, `ovton track`).
#include "ov_core/io/dataset.h"
#include "ov_eval/track_truth.h"
#include "ov_sim/simulator.h"
#include "test_util.h"

#include <gtest/gtest.h>

namespace {

struct NoiseFreeFlight {
  ovtest::TempDir tmp;
  ovton::core::Dataset data;
  std::vector<ovton::eval::TrackPoint> points;
  NoiseFreeFlight() {
    ovton::sim::SimOptions so;
    so.out_dir = tmp / "sim";
    so.duration_s = 4.0;
    so.seed = 5;
    so.features_only = true;
    so.features.pixel_noise = 0.0;
    ovton::sim::write_simulation(so);
    data = ovton::core::load_dataset(so.out_dir);
    points = ovton::eval::read_track_points(tmp / "sim/mav0/cam0/features.csv");
  }
};

} // namespace

TEST(TrackTruth, ExactTracksScoreZeroAndPlantedNoiseIsMeasured) {
  NoiseFreeFlight f;
  ASSERT_GT(f.points.size(), 1000u);
  const ovton::eval::TrackTruthResult exact = ovton::eval::score_tracks(f.points, f.data);
  EXPECT_GT(exact.obs_scored, static_cast<long>(f.points.size()) / 2);
  EXPECT_LT(exact.sigma_px, 0.01);
  EXPECT_EQ(exact.frac_gt1, 0.0);

  // White noise of 0.5 px: the dof-corrected sigma reads it back; consecutive errors are uncorrelated but for the
  // point fit, which makes residuals slightly anti-correlated (~ -1/n over a segment of n observations).
  const auto white = ovton::eval::rewrite_tracks(f.points, f.data, ovton::eval::TrackRewrite::White, 0.5, 0.0, 1);
  const ovton::eval::TrackTruthResult w = ovton::eval::score_tracks(white, f.data);
  EXPECT_NEAR(w.sigma_px, 0.5, 0.05);
  EXPECT_NEAR(w.lag1_corr, -0.1, 0.1);
  EXPECT_NEAR(w.mean_u, 0.0, 0.02);

  // Noise correlated along the track (KLT drift) shows as lag-1 correlation.
  const auto ar1 = ovton::eval::rewrite_tracks(f.points, f.data, ovton::eval::TrackRewrite::Ar1, 0.5, 0.9, 1);
  EXPECT_GT(ovton::eval::score_tracks(ar1, f.data).lag1_corr, 0.5);
}
