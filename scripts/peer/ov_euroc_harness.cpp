// Tiny ROS-free OpenVINS harness for EuRoC-ASL folders (cam0 + imu0, or cam0 + cam1 with stereo=1), ground-truth
// initialisation. ovton's copy of ../shared/peer/openvins_harness/ov_euroc_harness.cpp (issue 40): with stereo=0 (the
// default) it configures and feeds OpenVINS exactly as that file does; stereo=1 gives OpenVINS both EuRoC cameras
// (use_stereo=true, max_cameras=2, cam1's intrinsics, distortion and T_BS from mav0/cam1/sensor.yaml) and feeds the
// two images of each stamp together (ov_core::CameraData, sensor_ids {0, 1}). Built outside the tree against OV_ROOT
// (scripts/peer/CMakeLists.txt); no OpenVINS code is part of this file.
// A folder without ground truth (issue 37's phone recording, written by `ovton calibrate --out`) needs three keys
// that leave the defaults unchanged: init=ov, camchain=FILE, td0=S.
// Usage: ov_euroc_harness DATASET OUT_PREFIX [key=value ...]
//   keys: max_slam (0) num_pts (200) max_clones (11) sigma_px (1) calib_ext (0) calib_int (0) threads (1)
//   fast_threshold (20)
//         stereo (0)
//         init (gt): gt = OpenVINS's state from mav0/state_groundtruth_estimate0 at the first image;
//                    ov = OpenVINS's own initialiser (init_dyn_use=true: dynamic when moving, static on a jerk
//                    after stillness); rows are written from the first frame after it succeeded
//         camchain (none): a Kalibr camchain-imucam.yaml (T_cam_imu or T_imu_cam, intrinsics, radtan distortion,
//                    timeshift_cam_imu; e.g. ovton calibrate's OUT/kalibr/camchain-imucam.yaml) given to OpenVINS
//                    as its kalibr_imucam_chain.yaml instead of the one written from mav0/cam0/sensor.yaml (mono)
//         td0 (none): OpenVINS's initial calib_dt [s] (timeshift_cam_imu; default: the camchain's, else 0)
// Writes OUT_PREFIX.csv  : timestamp_ns(IMU
// clock),px,py,pz,qw,qx,qy,qz,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz,td_s,td_sigma_s,
//                          t_cam_ns,feed_ms,n_clones,n_slam,n_msckf_used,n_tracked
//        OUT_PREFIX_timing.txt, OUT_PREFIX_config/ (the YAML files OpenVINS loaded).
// Convention: OpenVINS calib_dt: t_imu = t_cam + calib_dt (State.h), same as ovton.
#include "core/VioManager.h"
#include "core/VioManagerOptions.h"
#include "state/State.h"
#include "state/StateHelper.h"
#include "utils/opencv_yaml_parse.h"
#include "utils/print.h"
#include "utils/quat_ops.h"

#include "euroc_folder_io.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <sys/stat.h>
#include <vector>

using Clock = std::chrono::steady_clock;
// Exposes the number of features the front end currently tracks (for the report only).
struct VM : ov_msckf::VioManager {
  using ov_msckf::VioManager::VioManager;
  size_t n_tracked() {
    auto o = trackFEATS->get_last_obs();
    return o.count(0) ? o.at(0).size() : 0;
  }
  // OpenVINS starts its tracker with init_max_features (50) and raises it to num_pts only inside its own
  // initializer (VioManagerHelper.cpp, try_to_initialize); initialize_with_gt skips that, so do it here.
  void set_num_features(int n) { trackFEATS->set_num_features(n); }
};
static double ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

using peer_io::read_csv;

static Eigen::Matrix4d read_TBS(cv::FileStorage &fs) {
  cv::FileNode d = fs["T_BS"]["data"];
  Eigen::Matrix4d T;
  for (int i = 0; i < 16; i++)
    T(i / 4, i % 4) = (double)d[i];
  return T;
}
static std::vector<double> read_vec(cv::FileStorage &fs, const char *k) {
  std::vector<double> v;
  for (auto it = fs[k].begin(); it != fs[k].end(); ++it)
    v.push_back((double)*it);
  return v;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    std::cerr << "usage: ov_euroc_harness DATASET OUT_PREFIX [max_slam=0 num_pts=200 max_clones=11 sigma_px=1 "
                 "calib_ext=0 calib_int=0 threads=1 fast_threshold=20]\n";
    return 2;
  }
  std::string ds = argv[1], out = argv[2];
  std::map<std::string, std::string> kv = {{"max_slam", "0"}, {"num_pts", "200"},       {"max_clones", "11"},
                                           {"sigma_px", "1"}, {"calib_ext", "0"},       {"calib_int", "0"},
                                           {"threads", "1"},  {"fast_threshold", "20"}, {"stereo", "0"},
                                           {"init", "gt"},    {"camchain", ""},         {"td0", ""}};
  for (int i = 3; i < argc; i++) {
    std::string a = argv[i];
    auto p = a.find('=');
    if (p == std::string::npos || !kv.count(a.substr(0, p))) {
      std::cerr << "bad option " << a << "\n";
      return 2;
    }
    kv[a.substr(0, p)] = a.substr(p + 1);
  }
  if (kv["init"] != "gt" && kv["init"] != "ov") {
    std::cerr << "init=gt or init=ov\n";
    return 2;
  }
  const std::string mav0 = ds + "/mav0/";

  // ---- calibration from the folder's sensor.yaml files
  // cv::FileStorage needs a "%YAML:1.0" first line, which the original EuRoC sensor.yaml files lack: read via a string.
  auto yaml_text = [](const std::string &path) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    std::string t = ss.str();
    return t.rfind("%YAML", 0) == 0 ? t : "%YAML:1.0\n" + t;
  };
  cv::FileStorage fc(yaml_text(mav0 + "cam0/sensor.yaml"), cv::FileStorage::READ | cv::FileStorage::MEMORY),
      fi(yaml_text(mav0 + "imu0/sensor.yaml"), cv::FileStorage::READ | cv::FileStorage::MEMORY);
  if (!fc.isOpened() || !fi.isOpened()) {
    std::cerr << "cannot read sensor.yaml\n";
    return 2;
  }
  Eigen::Matrix4d T_B_C = read_TBS(fc), T_B_I = read_TBS(fi);
  Eigen::Matrix4d T_I_C = T_B_I.inverse() * T_B_C; // camera -> IMU (kalibr T_imu_cam)
  auto intr = read_vec(fc, "intrinsics"), dist = read_vec(fc, "distortion_coefficients"),
       res = read_vec(fc, "resolution");
  std::string dmodel = (std::string)fc["distortion_model"];
  if (dmodel != "radial-tangential" && dmodel != "radtan") {
    std::cerr << "unsupported distortion " << dmodel << "\n";
    return 2;
  }
  // stereo=1: cam1 from its own sensor.yaml (EuRoC's T_BS, pinhole radial-tangential)
  const bool stereo = kv["stereo"] == "1";
  Eigen::Matrix4d T_I_C1 = Eigen::Matrix4d::Identity();
  std::vector<double> intr1, dist1, res1;
  if (stereo) {
    cv::FileStorage fc1(yaml_text(mav0 + "cam1/sensor.yaml"), cv::FileStorage::READ | cv::FileStorage::MEMORY);
    if (!fc1.isOpened()) {
      std::cerr << "stereo=1 needs mav0/cam1/sensor.yaml\n";
      return 2;
    }
    T_I_C1 = T_B_I.inverse() * read_TBS(fc1);
    intr1 = read_vec(fc1, "intrinsics"), dist1 = read_vec(fc1, "distortion_coefficients"),
    res1 = read_vec(fc1, "resolution");
    const std::string dmodel1 = (std::string)fc1["distortion_model"];
    if (dmodel1 != "radial-tangential" && dmodel1 != "radtan") {
      std::cerr << "unsupported cam1 distortion " << dmodel1 << "\n";
      return 2;
    }
  }
  double gnd = (double)fi["gyroscope_noise_density"], grw = (double)fi["gyroscope_random_walk"];
  double and_ = (double)fi["accelerometer_noise_density"], arw = (double)fi["accelerometer_random_walk"];
  double imu_rate = (double)fi["rate_hz"];

  // ---- write the OpenVINS config (EuRoC estimator_config.yaml, monocular)
  const std::string cfg = out + "_config";
  mkdir(cfg.c_str(), 0755);
  {
    // Start from OpenVINS's own config/euroc_mav/*.yaml (every key present) and override what this comparison sets.
    auto rewrite = [](const std::string &src, const std::string &dst, const std::map<std::string, std::string> &ov) {
      std::ifstream in(src);
      if (!in) {
        std::cerr << "cannot read template " << src << "\n";
        std::exit(2);
      }
      std::ofstream outf(dst);
      std::string line;
      std::map<std::string, int> used;
      while (std::getline(in, line)) {
        size_t ind = line.find_first_not_of(' ');
        if (ind != std::string::npos) {
          size_t colon = line.find(':', ind);
          if (colon != std::string::npos) {
            std::string key = line.substr(ind, colon - ind);
            auto it = ov.find(key);
            if (it != ov.end()) {
              line = line.substr(0, ind) + key + ": " + it->second;
              used[key]++;
            }
          }
        }
        outf << line << "\n";
      }
      for (auto &kvp : ov)
        if (!used.count(kvp.first)) {
          std::cerr << "template " << src << " lacks key " << kvp.first << "\n";
          std::exit(2);
        }
    };
    auto num = [](double x) {
      std::ostringstream ss;
      ss.precision(12);
      ss << x;
      return ss.str();
    };
    const char *ov_root = std::getenv("OV_ROOT"); // OpenVINS source tree: its config/euroc_mav is the template
    const std::string tmpl = std::string(ov_root ? ov_root : "openvins") + "/config/euroc_mav/";
    rewrite(tmpl + "estimator_config.yaml", cfg + "/estimator_config.yaml",
            {{"verbosity", "\"WARNING\""},
             {"use_stereo", stereo ? "true" : "false"},
             {"max_cameras", stereo ? "2" : "1"},
             {"calib_cam_extrinsics", kv["calib_ext"] == "1" ? "true" : "false"},
             {"calib_cam_intrinsics", kv["calib_int"] == "1" ? "true" : "false"},
             {"calib_cam_timeoffset", "true"},
             {"max_clones", kv["max_clones"]},
             {"max_slam", kv["max_slam"]},
             {"init_dyn_use", kv["init"] == "ov" ? "true" : "false"},
             {"init_dyn_mle_max_threads", kv["threads"]},
             {"try_zupt", "false"},
             {"use_klt", "true"},
             {"num_pts", kv["num_pts"]},
             {"fast_threshold", kv["fast_threshold"]},
             {"num_opencv_threads", kv["threads"]},
             {"use_aruco", "false"},
             {"up_msckf_sigma_px", kv["sigma_px"]},
             {"up_slam_sigma_px", kv["sigma_px"]},
             {"record_timing_information", "false"},
             {"save_total_state", "false"}});
    rewrite(tmpl + "kalibr_imu_chain.yaml", cfg + "/kalibr_imu_chain.yaml",
            {{"accelerometer_noise_density", num(and_)},
             {"accelerometer_random_walk", num(arw)},
             {"gyroscope_noise_density", num(gnd)},
             {"gyroscope_random_walk", num(grw)},
             {"update_rate", num(imu_rate)}});
    std::ofstream c(cfg + "/kalibr_imucam_chain.yaml");
    c.precision(15);
    c << "%YAML:1.0\n";
    auto cam_block = [&c](int id, const Eigen::Matrix4d &T, const std::vector<double> &dist,
                          const std::vector<double> &intr, const std::vector<double> &res,
                          const std::string &overlaps) {
      c << "\ncam" << id << ":\n  T_imu_cam:\n";
      for (int r = 0; r < 4; r++)
        c << "    - [" << T(r, 0) << ", " << T(r, 1) << ", " << T(r, 2) << ", " << T(r, 3) << "]\n";
      c << "  cam_overlaps: " << overlaps << "\n  camera_model: pinhole\n  distortion_coeffs: [" << dist[0] << ", "
        << dist[1] << ", " << dist[2] << ", " << dist[3] << "]\n  distortion_model: radtan\n  intrinsics: [" << intr[0]
        << ", " << intr[1] << ", " << intr[2] << ", " << intr[3] << "]\n  resolution: [" << (int)res[0] << ", "
        << (int)res[1] << "]\n  timeshift_cam_imu: 0.0\n  rostopic: /cam" << id << "/image_raw\n";
    };
    cam_block(0, T_I_C, dist, intr, res, stereo ? "[1]" : "[]");
    if (stereo)
      cam_block(1, T_I_C1, dist1, intr1, res1, "[0]");
  }
  if (!kv["camchain"].empty() || !kv["td0"].empty()) {
    // camchain=FILE: that file's text instead (a "%YAML:1.0" line put first when it lacks one); td0=S: its
    // timeshift_cam_imu replaced (OpenVINS reads cam0's as calib_camimu_dt, t_imu = t_cam + calib_dt)
    if (!kv["camchain"].empty() && stereo) {
      std::cerr << "camchain= is for a monocular run\n";
      return 2;
    }
    const std::string src = kv["camchain"].empty() ? cfg + "/kalibr_imucam_chain.yaml" : kv["camchain"];
    if (!std::ifstream(src)) {
      std::cerr << "cannot read " << src << "\n";
      return 2;
    }
    std::string text = yaml_text(src);
    // A block sequence at its key's indentation ("  T_cam_imu:" then "  - [...]": valid YAML, Kalibr's layout, and
    // ovton's before 60d91f7) is refused by OpenCV's FileStorage ("Incorrect indentation"): indent such items by two.
    {
      std::istringstream in(text);
      std::string line, fixed;
      size_t key_indent = std::string::npos; // indentation of the last "key:" line without a value
      while (std::getline(in, line)) {
        const size_t ind = line.find_first_not_of(' ');
        if (ind != std::string::npos && line.compare(ind, 2, "- ") == 0) {
          if (key_indent != std::string::npos && ind <= key_indent)
            line.insert(0, key_indent + 2 - ind, ' ');
        } else if (ind != std::string::npos && line.back() == ':') {
          key_indent = ind;
        } else if (ind != std::string::npos) {
          key_indent = std::string::npos;
        }
        fixed += line + "\n";
      }
      text = fixed;
    }
    if (!kv["td0"].empty()) {
      const size_t k = text.find("timeshift_cam_imu:");
      if (k == std::string::npos) {
        std::cerr << "no timeshift_cam_imu in the camchain\n";
        return 2;
      }
      const size_t e = text.find('\n', k);
      text.replace(k, (e == std::string::npos ? text.size() : e) - k, "timeshift_cam_imu: " + kv["td0"]);
    }
    std::ofstream(cfg + "/kalibr_imucam_chain.yaml") << text;
  }
  auto parser = std::make_shared<ov_core::YamlParser>(cfg + "/estimator_config.yaml");
  std::string verbosity = "WARNING";
  parser->parse_config("verbosity", verbosity);
  ov_core::Printer::setPrintLevel(verbosity);
  ov_msckf::VioManagerOptions params;
  params.print_and_load(parser);
  if (!parser->successful()) {
    std::cerr << "config parse failed\n";
    return 2;
  }
  auto sys = std::make_shared<VM>(params);

  // ---- data
  const std::vector<ov_core::ImuData> imu = peer_io::load_imu(mav0);
  const std::vector<peer_io::Image> imgs = peer_io::load_images(mav0, "cam0");
  // stereo: cam1's image of each cam0 stamp (EuRoC's cameras are triggered together: same stamps); a stamp cam1
  // lacks is fed to OpenVINS as a monocular frame of cam0 (its tracker takes one image or a stereo pair)
  std::map<int64_t, std::string> cam1_of;
  if (stereo)
    for (const peer_io::Image &im : peer_io::load_images(mav0, "cam1"))
      cam1_of[im.t] = im.path;
  int n_pairs = 0;
  // ground truth at the first image (camera clock = IMU clock under the initial guess t_d = 0), linear interpolation
  const int64_t t0 = imgs.front().t;
  const bool own_init = kv["init"] == "ov";
  if (!own_init) {
    Eigen::Matrix<double, 17, 1> imustate;
    if (!peer_io::ground_truth_state(mav0, t0, imustate)) {
      std::cerr << "no ground truth at first image (init=ov: OpenVINS's own initialiser)\n";
      return 2;
    }
    sys->initialize_with_gt(imustate);
    sys->set_num_features(params.num_pts / params.state_options.num_cameras);
  }
  int n_before_init = 0; // init=ov: frames fed before OpenVINS's initialiser succeeded (no rows)

  // ---- replay in time order (images queued until an IMU sample past t_cam + calib_dt exists, as the OpenVINS ROS node
  // does)
  std::ofstream o(out + ".csv");
  o << "timestamp_ns,px,py,pz,qw,qx,qy,qz,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz,td_s,td_sigma_s,t_cam_ns,feed_ms,n_clones,n_"
       "slam,n_msckf_used,n_tracked\n";
  char buf[1024];
  double feed_total = 0, load_total = 0;
  int n_frames = 0;
  std::vector<double> feed_ms_all;
  size_t ii = 0, ci = 0;
  auto L0 = Clock::now();
  while (ci < imgs.size()) {
    auto state = sys->get_state();
    const double dt = state->_calib_dt_CAMtoIMU->value()(0);
    const double t_need = imgs[ci].t * 1e-9 + dt;
    if (ii < imu.size() && (ii == 0 || imu[ii - 1].timestamp <= t_need)) {
      sys->feed_measurement_imu(imu[ii++]);
      continue;
    }
    if (ii >= imu.size() && imu.back().timestamp <= t_need)
      break; // no IMU beyond this image
    auto a = Clock::now();
    cv::Mat im = cv::imread(imgs[ci].path, cv::IMREAD_GRAYSCALE);
    cv::Mat im1;
    auto it1 = stereo ? cam1_of.find(imgs[ci].t) : cam1_of.end();
    if (it1 != cam1_of.end()) {
      im1 = cv::imread(it1->second, cv::IMREAD_GRAYSCALE);
      if (im1.empty()) {
        std::cerr << "unreadable " << it1->second << "\n";
        return 3;
      }
    }
    auto b = Clock::now();
    if (im.empty()) {
      std::cerr << "unreadable " << imgs[ci].path << "\n";
      return 3;
    }
    ov_core::CameraData cd;
    cd.timestamp = imgs[ci].t * 1e-9;
    cd.sensor_ids.push_back(0);
    cd.images.push_back(im);
    cd.masks.push_back(cv::Mat::zeros(im.rows, im.cols, CV_8UC1));
    if (!im1.empty()) {
      cd.sensor_ids.push_back(1);
      cd.images.push_back(im1);
      cd.masks.push_back(cv::Mat::zeros(im1.rows, im1.cols, CV_8UC1));
      n_pairs++;
    }
    sys->feed_measurement_camera(cd);
    auto c = Clock::now();
    load_total += ms(a, b);
    const double f = ms(b, c);
    feed_total += f;
    feed_ms_all.push_back(f);
    n_frames++;
    if (own_init && !sys->initialized()) {
      n_before_init++;
      ci++;
      continue;
    }
    state = sys->get_state();
    const double td = state->_calib_dt_CAMtoIMU->value()(0);
    std::vector<std::shared_ptr<ov_type::Type>> vars = {state->_calib_dt_CAMtoIMU};
    const double tds = std::sqrt(std::max(0.0, ov_msckf::StateHelper::get_marginal_covariance(state, vars)(0, 0)));
    Eigen::Vector4d qj = state->_imu->quat(); // JPL q_GtoI (x,y,z,w) == Hamilton q_WB components
    Eigen::Vector3d p = state->_imu->pos(), v = state->_imu->vel(), bg = state->_imu->bias_g(),
                    ba = state->_imu->bias_a();
    const int64_t t_imu_ns = (int64_t)std::llround((state->_timestamp + td) * 1e9);
    snprintf(buf, sizeof(buf),
             "%lld,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.6f,%.6f,%.6f,%.7f,%.7f,%.7f,%.6f,%.6f,%.6f,%.9f,%.9f,%lld,%.3f,"
             "%zu,%zu,%zu,%zu\n",
             (long long)t_imu_ns, p(0), p(1), p(2), qj(3), qj(0), qj(1), qj(2), v(0), v(1), v(2), bg(0), bg(1), bg(2),
             ba(0), ba(1), ba(2), td, tds, (long long)imgs[ci].t, f, state->_clones_IMU.size(),
             state->_features_SLAM.size(), sys->get_good_features_MSCKF().size(), sys->n_tracked());
    o << buf;
    ci++;
  }
  auto L1 = Clock::now();
  const double loop_ms = ms(L0, L1);
  const double span_s = (imgs[n_frames - 1].t - imgs[0].t) * 1e-9 + 0.05;
  std::sort(feed_ms_all.begin(), feed_ms_all.end());
  if (stereo)
    std::cout << "stereo pairs " << n_pairs << " of " << n_frames << " frames\n";
  if (own_init)
    std::cout << "init=ov: " << n_before_init << " frames before OpenVINS's initialiser succeeded\n";
  std::ofstream t(out + "_timing.txt");
  snprintf(buf, sizeof(buf),
           "frames %d\nfeed_measurement_camera ms/frame mean %.3f median %.3f p95 %.3f\nimage load ms/frame %.3f\n"
           "whole loop (IMU feed + PNG load + camera feed) ms/frame %.3f total_s %.3f\ndata span s %.3f  real-time "
           "multiple (loop) %.2f  "
           "(estimator only) %.2f\n",
           n_frames, feed_total / n_frames, feed_ms_all[feed_ms_all.size() / 2],
           feed_ms_all[(size_t)(0.95 * feed_ms_all.size())], load_total / n_frames, loop_ms / n_frames, loop_ms / 1e3,
           span_s, span_s / (loop_ms / 1e3), span_s / (feed_total / 1e3));
  t << buf;
  std::cout << buf;
  return 0;
}
