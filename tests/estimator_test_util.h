#pragma once
// Whole runs in the tests, made as `ovton run` makes them: the library's Estimator fed by its player. A test that wants
// to look inside the filter after each image attaches peek(...).
#include "ov_core/io/dataset.h"
#include "ov_msckf_ton/estimator/dataset_player.h"
#include "ov_msckf_ton/estimator/estimator.h"

#include <functional>
#include <memory>
#include <vector>

namespace ovtest {

struct EstimatorRun {
  std::vector<ovton::core::StateSample> traj;
  ovton::EstimatorReport report;
  ovton::PlayResult play;
};

/// Plays `data` through an Estimator with `opt` exactly (the dataset's ground truth and true offset as aids), on the
/// calling thread unless `threaded`. What the estimator throws passes through.
inline EstimatorRun run_estimator(const ovton::core::Dataset &data, const ovton::msckf::VioOptions &opt,
                                  std::vector<std::shared_ptr<ovton::msckf::FilterObserver>> observers = {},
                                  bool threaded = false) {
  EstimatorRun r;
  ovton::EstimatorSetup setup = ovton::setup_for(data, opt);
  setup.threaded = threaded;
  ovton::Estimator est(std::move(setup));
  est.add_state_callback([&r](const ovton::core::StateSample &s) { r.traj.push_back(s); });
  for (auto &o : observers)
    est.add_observer(std::move(o));
  r.play = ovton::play(data, est);
  r.report = est.report();
  return r;
}

/// An observer that hands the filter to `fn` after each image (its state, networks, counters).
inline std::shared_ptr<ovton::msckf::FilterObserver> peek(std::function<void(const ovton::msckf::VioManager &)> fn) {
  struct Peek : ovton::msckf::FilterObserver {
    std::function<void(const ovton::msckf::VioManager &)> fn;
    void on_filter(const ovton::msckf::VioManager &f) override { fn(f); }
  };
  auto p = std::make_shared<Peek>();
  p->fn = std::move(fn);
  return p;
}

} // namespace ovtest
