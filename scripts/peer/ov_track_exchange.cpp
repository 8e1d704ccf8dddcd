// Track exchange with OpenVINS (peer comparison; built outside this repository against an OpenVINS source tree by
// scripts/peer/openvins_vs_ovton.sh --exchange; no OpenVINS code is in this file, it only calls its public API).
// Runs OpenVINS's VioManager monocular on an EuRoC folder, initialised from ground truth at the first image, with the
// configuration the shared harness (../shared/peer/openvins_harness) wrote for that folder, and either
//   dump=FILE  tracks the images with OpenVINS's own KLT front end and writes every tracked point per image as
//              timestamp_ns,feature_id,u,v (ovton's cam0/features.csv format: ovton's estimator on OpenVINS's tracks),
//              or
//   feed=FILE  skips the images and feeds OpenVINS's estimator the tracks of a features.csv (e.g. `ovton track --out`:
//              OpenVINS's estimator on ovton's tracks).
// Usage: ov_track_exchange DATASET OUT_PREFIX CONFIG_DIR/estimator_config.yaml (dump=FILE | feed=FILE) [num_pts=200]
// Writes OUT_PREFIX.csv with ovton's 19 trajectory columns (IMU clock) plus t_cam_ns,feed_ms,n_msckf_used.
#include "core/VioManager.h"
#include "core/VioManagerOptions.h"
#include "state/State.h"
#include "state/StateHelper.h"
#include "utils/opencv_yaml_parse.h"
#include "utils/print.h"
#include "utils/quat_ops.h"

#include "euroc_folder_io.h"

#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct VM : ov_msckf::VioManager {
  using ov_msckf::VioManager::VioManager;
  void set_num_features(int n) { trackFEATS->set_num_features(n); }
  void last_tracks(std::vector<std::pair<size_t, cv::Point2f>> &out) {
    out.clear();
    auto obs = trackFEATS->get_last_obs();
    auto ids = trackFEATS->get_last_ids();
    if (!obs.count(0))
      return;
    for (size_t i = 0; i < obs.at(0).size(); i++)
      out.emplace_back(ids.at(0).at(i), obs.at(0).at(i).pt);
  }
};

using peer_io::read_csv;

} // namespace

int main(int argc, char **argv) {
  if (argc < 5) {
    std::cerr
        << "usage: ov_track_exchange DATASET OUT_PREFIX ESTIMATOR_CONFIG.yaml (dump=FILE | feed=FILE) [num_pts=200]\n";
    return 2;
  }
  const std::string ds = argv[1], out = argv[2], cfg = argv[3];
  std::string dump, feed;
  int num_pts = 200;
  for (int i = 4; i < argc; i++) {
    const std::string a = argv[i];
    if (a.rfind("dump=", 0) == 0)
      dump = a.substr(5);
    else if (a.rfind("feed=", 0) == 0)
      feed = a.substr(5);
    else if (a.rfind("num_pts=", 0) == 0)
      num_pts = std::stoi(a.substr(8));
    else {
      std::cerr << "bad option " << a << "\n";
      return 2;
    }
  }
  if (dump.empty() == feed.empty()) {
    std::cerr << "give exactly one of dump=FILE and feed=FILE\n";
    return 2;
  }
  auto parser = std::make_shared<ov_core::YamlParser>(cfg);
  ov_core::Printer::setPrintLevel("WARNING");
  ov_msckf::VioManagerOptions params;
  params.print_and_load(parser);
  if (!parser->successful()) {
    std::cerr << "config parse failed: " << cfg << "\n";
    return 2;
  }
  auto sys = std::make_shared<VM>(params);
  const std::string mav0 = ds + "/mav0/";
  const std::vector<ov_core::ImuData> imu = peer_io::load_imu(mav0);
  const std::vector<peer_io::Image> imgs = peer_io::load_images(mav0, "cam0");
  std::map<int64_t, std::vector<std::pair<size_t, Eigen::VectorXf>>> fed;
  if (!feed.empty())
    for (auto &r : read_csv(feed)) {
      Eigen::VectorXf uv(2);
      uv << std::stof(r[2]), std::stof(r[3]);
      fed[std::stoll(r[0])].emplace_back(std::stoull(r[1]), uv);
    }
  // Ground truth at the first image (linear interpolation), as the shared harness does.
  const int64_t t0 = imgs.front().t;
  Eigen::Matrix<double, 17, 1> s0;
  if (!peer_io::ground_truth_state(mav0, t0, s0)) {
    std::cerr << "no ground truth at first image\n";
    return 2;
  }
  sys->initialize_with_gt(s0);
  sys->set_num_features(num_pts);

  std::ofstream o(out + ".csv"), d;
  if (!dump.empty()) {
    d.open(dump);
    d << "#timestamp_ns,feature_id,u,v\n";
  }
  o << "timestamp_ns,px,py,pz,qw,qx,qy,qz,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz,td_s,td_sigma_s,t_cam_ns,feed_ms,n_msckf_"
       "used\n";
  char buf[1024];
  std::vector<std::pair<size_t, cv::Point2f>> tracks;
  size_t ii = 0, ci = 0;
  double feed_total = 0;
  int frames = 0;
  while (ci < imgs.size()) {
    auto state = sys->get_state();
    const double t_need = imgs[ci].t * 1e-9 + state->_calib_dt_CAMtoIMU->value()(0);
    if (ii < imu.size() && (ii == 0 || imu[ii - 1].timestamp <= t_need)) {
      sys->feed_measurement_imu(imu[ii++]);
      continue;
    }
    if (ii >= imu.size() && imu.back().timestamp <= t_need)
      break;
    const auto a = std::chrono::steady_clock::now();
    if (feed.empty()) {
      cv::Mat im = cv::imread(imgs[ci].path, cv::IMREAD_GRAYSCALE);
      if (im.empty()) {
        std::cerr << "unreadable " << imgs[ci].path << "\n";
        return 3;
      }
      ov_core::CameraData cd;
      cd.timestamp = imgs[ci].t * 1e-9;
      cd.sensor_ids.push_back(0);
      cd.images.push_back(im);
      cd.masks.push_back(cv::Mat::zeros(im.rows, im.cols, CV_8UC1));
      sys->feed_measurement_camera(cd);
      sys->last_tracks(tracks);
      for (auto &[id, p] : tracks) {
        std::snprintf(buf, sizeof(buf), "%lld,%zu,%.9g,%.9g\n", (long long)imgs[ci].t, id, p.x, p.y);
        d << buf;
      }
    } else {
      std::vector<std::vector<std::pair<size_t, Eigen::VectorXf>>> feats(1);
      auto it = fed.find(imgs[ci].t);
      if (it != fed.end())
        feats[0] = it->second;
      sys->feed_measurement_simulation(imgs[ci].t * 1e-9, {0}, feats);
    }
    const double f = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count();
    feed_total += f;
    frames++;
    state = sys->get_state();
    const double td = state->_calib_dt_CAMtoIMU->value()(0);
    std::vector<std::shared_ptr<ov_type::Type>> vars = {state->_calib_dt_CAMtoIMU};
    const double tds = std::sqrt(std::max(0.0, ov_msckf::StateHelper::get_marginal_covariance(state, vars)(0, 0)));
    const Eigen::Vector4d qj = state->_imu->quat();
    const Eigen::Vector3d p = state->_imu->pos(), v = state->_imu->vel(), bg = state->_imu->bias_g(),
                          ba = state->_imu->bias_a();
    std::snprintf(buf, sizeof(buf),
                  "%lld,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.6f,%.6f,%.6f,%.7f,%.7f,%.7f,%.6f,%.6f,%.6f,%.9f,%.9f,%lld,"
                  "%.3f,%zu\n",
                  (long long)std::llround((state->_timestamp + td) * 1e9), p(0), p(1), p(2), qj(3), qj(0), qj(1), qj(2),
                  v(0), v(1), v(2), bg(0), bg(1), bg(2), ba(0), ba(1), ba(2), td, tds, (long long)imgs[ci].t, f,
                  sys->get_good_features_MSCKF().size());
    o << buf;
    ci++;
  }
  std::printf("frames %d estimator ms/frame %.3f\n", frames, frames ? feed_total / frames : 0.0);
  return 0;
}
