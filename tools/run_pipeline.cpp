#include "tools/run_pipeline.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_msckf_ton/estimator/mcap_run_recorder.h"
#include "tools/progress.h"

namespace ovton::cli {

RunResult run_dataset(const ovton::core::Dataset &data, const RunRequest &req) {
  RunResult res;
  EstimatorSetup setup = setup_for(data, req.opt);
  setup.threaded = req.threaded;
  Estimator est(std::move(setup));
  std::unique_ptr<ovton::core::TrajectoryWriter> writer;
  if (!req.output.empty())
    writer = std::make_unique<ovton::core::TrajectoryWriter>(
        req.output, req.tum ? ovton::core::TrajectoryFormat::Tum : ovton::core::TrajectoryFormat::Csv,
        req.opt.td.per_camera && ovton::msckf::estimates_td(req.opt.td.mode) ? static_cast<int>(est.camera_count()) - 1
                                                                             : 0);
  std::unique_ptr<ovton::eval::NeesAccumulator> nees;
  if (req.opt.init.mode == ovton::msckf::InitMode::GroundTruth)
    nees = std::make_unique<ovton::eval::NeesAccumulator>(data.groundtruth, data.td_truth);
  est.add_state_callback([&](const ovton::core::StateSample &s) {
    if (writer)
      writer->write(s);
    if (nees)
      nees->add(s);
    res.traj.push_back(s);
  });
  if (!req.residual_log.empty())
    est.add_observer(std::make_shared<ovton::msckf::ResidualLogObserver>(req.residual_log));
  if (!req.velocity_log.empty())
    est.add_observer(std::make_shared<ovton::msckf::VelocityLogObserver>(req.velocity_log));
  for (const auto &o : req.observers)
    est.add_observer(o);
  std::shared_ptr<McapRunRecorder> recording; // closed by its destructor when the run throws
  if (!req.mcap_out.empty()) {
    ovton::core::RunMcapOptions mo = req.mcap;
    mo.T_BC = data.imu_calib.T_BI.inverse() * data.cam.T_BC; // camera -> IMU (the state's body)
    recording = McapRunRecorder::attach(est, req.mcap_out, mo);
    recording->set_truth(data.groundtruth, data.td_truth);
  }

  ProgressBar bar(req.label.empty() ? "run " + ovton::msckf::to_string(req.opt.td.mode) : req.label, !req.progress);
  PlayOptions po;
  po.max_images = req.max_images;
  po.pace = req.pace;
  bool search_said = false;
  // The search's outcome as soon as it is known, so that it is seen even when the run fails later.
  const auto say_search = [&](const EstimatorStatus &st) {
    if (st.td_search && !search_said && req.progress) {
      bar.say("coarse t_d search: " + st.td_search->summary());
      search_said = true;
    }
  };
  po.on_progress = [&](size_t i, size_t n) {
    const EstimatorStatus st = est.status();
    say_search(st);
    char extra[64];
    std::snprintf(extra, sizeof(extra), "t_d %.3f ms", st.td_s * 1e3);
    bar.update(i, n, extra);
    if (req.on_progress)
      req.on_progress(i, n);
    return !interrupted();
  };
  try {
    res.play = play(data, est, po);
  } catch (...) {
    say_search(est.status());
    bar.finish();
    throw;
  }
  say_search(est.status());
  bar.finish();
  res.report = est.report();
  if (recording) {
    recording->close();
    res.mcap_counts = recording->message_counts();
  }
  if (nees)
    res.nees = nees->stats();
  return res;
}

} // namespace ovton::cli
