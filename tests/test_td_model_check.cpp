// The t_d model check's test (ov_msckf_ton/td/td_model_check.h) on synthetic sequences of corrections: it must fire on
// a persistent one-sign trend and stay quiet on what a right model also produces — one large jump (a filter converging
// from far off, an outlier's kick) and corrections of alternating sign. The real cut end to end is in test_real_td.cpp.
#include "ov_msckf_ton/core/vio_options.h"
#include "ov_msckf_ton/td/td_model_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

using ovton::msckf::TdTrendTest;

namespace {

/// 20 updates a second for dur_s seconds; t_d's variance falls as a constant's does when every image brings the same
/// information (sigma 10 ms a priori, 0.5 ms after 4 s), and update k moves the mean by delta(k, t_s). Returns the time
/// of the first verdict that contradicts the model (-1: none) and, through `last`, the final verdict.
double first_fire_s(const TdTrendTest &proto, double dur_s, const std::function<double(int, double)> &delta,
                    TdTrendTest::Verdict *last = nullptr) {
  TdTrendTest test = proto;
  const double info0 = 1.0 / (10e-3 * 10e-3), info_per_update = 1.0 / (0.5e-3 * 0.5e-3) / 80.0;
  double td = 0.0, fired = -1.0;
  for (int k = 1; k <= static_cast<int>(dur_s * 20); ++k) {
    const double t_s = k / 20.0;
    const double var0 = 1.0 / (info0 + (k - 1) * info_per_update), var1 = 1.0 / (info0 + k * info_per_update);
    const double td1 = td + delta(k, t_s);
    test.add(static_cast<int64_t>(t_s * 1e9), td, var0, td1, var1);
    td = td1;
    const TdTrendTest::Verdict v = test.evaluate();
    if (v.contradicted && fired < 0)
      fired = t_s;
    if (last)
      *last = v;
  }
  return fired;
}

/// The test with the shipped thresholds.
TdTrendTest shipped() {
  const ovton::msckf::TimeOffsetOptions o;
  return TdTrendTest(o.model_check_window_s, o.model_check_z, o.model_check_min_step_s);
}

} // namespace

// A model trailing an offset that drifts 3 ms/s: the filter corrects about two thirds of each image's step, every time
// with one sign. Each 1-s stretch then moves t_d by 2 ms where, from 1 s on, the updates allow 0.3-0.8 ms.
TEST(TdModelCheck, FiresOnAPersistentOneSignTrend) {
  TdTrendTest::Verdict v;
  const double step = 2e-3 / 20;
  const double t = first_fire_s(
      shipped(), 4.45, [step](int, double) { return step; }, &v);
  std::cout << "[ measured ] trend: fired at " << t << " s, z " << v.z << ", moved " << v.moved_s * 1e3 << " ms\n";
  EXPECT_GT(t, 2.0 - 1e-9) << "it needs two full stretches of evidence";
  EXPECT_LT(t, 3.0);
  // The same trend the other way.
  EXPECT_GT(first_fire_s(shipped(), 4.45, [step](int, double) { return -step; }), 0.0);
}

// One jump of 20 ms (convergence from a far start, an outlier): one stretch sums far beyond its sigma, the other not.
TEST(TdModelCheck, StaysQuietOnASingleJump) {
  for (const double at_s : {0.5, 1.5, 2.5})
    EXPECT_LT(
        first_fire_s(shipped(), 4.45, [at_s](int k, double) { return k == static_cast<int>(at_s * 20) ? 20e-3 : 0; }),
        0.0)
        << "jump at " << at_s << " s";
}

// Corrections of alternating sign, each as large as the trend's: they cancel over any stretch.
TEST(TdModelCheck, StaysQuietOnAlternatingSigns) {
  const double step = 2e-3 / 20;
  EXPECT_LT(first_fire_s(shipped(), 4.45, [step](int k, double) { return (k % 2 ? 1.0 : -1.0) * step; }), 0.0);
  // ... and on a sign that flips once a second: each stretch moves, but two stretches in a row disagree.
  EXPECT_LT(
      first_fire_s(shipped(), 4.45,
                   [step](int, double t) { return (static_cast<int>(std::floor(t - 1e-9)) % 2 ? 1.0 : -1.0) * step; }),
      0.0);
}

// Below model_check_min_step_s a trend is of no consequence however tight the sigma: after a minute the updates allow
// ~0.02 ms a stretch, so a 0.05 ms/s walk sums to ~3 sigmas, and is left alone; 0.2 ms/s is not.
TEST(TdModelCheck, IgnoresATrendBelowTheMinimumStep) {
  EXPECT_LT(first_fire_s(shipped(), 60.0, [](int, double) { return 0.05e-3 / 20; }), 0.0);
  EXPECT_GT(first_fire_s(shipped(), 60.0, [](int, double) { return 0.2e-3 / 20; }), 0.0);
}
