// A gentle flight with a vibrating gyro: the clone's t_d Jacobian must not take the vibration for motion
// (docs/robustness.md, "Weak excitation").
#include "estimator_test_util.h"
#include "io_test_util.h"
#include "ov_core/io/dataset.h"
#include "ov_msckf_ton/core/vio_manager.h"
#include "ov_sim/realism.h"
#include "ov_sim/simulator.h"
#include "sim_fixture.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <utility>
// docs/robustness.md, "Weak excitation": a gentle flight (the built-in one, agility 0) with the realistic IMU, whose
// gyro vibrates as the real V1_01's does. With the gyro's single reading at the image in the clone's t_d Jacobian,
// `sr` started 10 ms off stops halfway with a sigma that claims far more (5.3 ± 0.27 ms at 20 s: a confident wrong
// answer); with the centred 0.1 s mean it ends near the truth with an honest sigma (7.9 ± 1.1 ms, 2.6 s here).
TEST(WeakExcitation, VibratingGyroDoesNotMakeTdLookObservable) {
  ovtest::TempDir tmp;
  ovton::sim::SimOptions o = ovtest::feature_sim(tmp / "sim", 20.0, 1);
  ovton::sim::apply_realism("euroc", o); // the IMU error model measured on real V1_01, its flight vibration included
  o.td.td0_s = 0.010;
  ovton::sim::write_simulation(o);
  const ovton::core::Dataset data = ovton::core::load_dataset(o.out_dir);
  const auto final_td = [&](double window_s) {
    ovton::msckf::VioOptions opt = ovtest::gt_run_options(ovton::msckf::TdMode::Sr, 0.0);
    opt.update.msckf.sigma_px = 1.0;
    opt.td.jacobian_rate_window_s = window_s;
    std::pair<double, double> last;
    ovtest::run_estimator(data, opt, {ovtest::peek([&](const ovton::msckf::VioManager &f) {
                            last = {f.state().td, f.state().td_sigma()};
                          })});
    return last;
  };
  const auto [td_reading, sd_reading] = final_td(0.0);
  const auto [td_mean, sd_mean] = final_td(0.1);
  std::cout << "[weak excitation] t_d " << td_reading * 1e3 << " +- " << sd_reading * 1e3 << " ms (reading), "
            << td_mean * 1e3 << " +- " << sd_mean * 1e3 << " ms (centred mean); truth 10 ms\n";
  EXPECT_GT(std::abs(td_reading - 0.010), 8 * sd_reading); // the failure this guards against is still there
  EXPECT_LT(std::abs(td_mean - 0.010), 3 * sd_mean);
  EXPECT_LT(std::abs(td_mean - 0.010), 0.004);
}
