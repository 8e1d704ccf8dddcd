// Renderer: geometry (a planted marker is drawn where the camera model projects it) and trackability
// (pyramidal KLT keeps enough long tracks on a rendered EuRoC stretch).
#include "ov_core/io/trajectory_io.h"
#include "ov_sim/euroc_calib.h"
#include "ov_sim/renderer.h"
#include "ov_sim/simulator.h"
#include "sim_test_util.h"
#include "test_util.h"

#include <algorithm>
#include <chrono>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

using namespace ovton::core;
using namespace ovton::sim;

using ovtest::dark_centroid;
using ovtest::median;

TEST(SimRender, PlantedMarkersAppearWhereTheCameraModelProjectsThem) {
  Scene scene = ovtest::marker_room();
  CameraModel cam(euroc_cam0_calib());
  const RenderOptions ro = ovtest::noise_free_rendering();
  // Camera at (0,0,1.5) looking along +x, slightly yawed and rolled so markers land off-centre (distortion).
  const Eigen::Matrix3d R_look = ovtest::look_along_x();
  const Eigen::Matrix3d R_WC = Eigen::AngleAxisd(0.15, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R_look *
                               Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d p_WC(0.2, -0.1, 1.5);
  struct Case {
    int surface;
    double u, v;
  };
  // +x wall: u along y, v along z (from the room's low corner), at the centre-left, top right, bottom.
  const std::vector<Case> cases = {{Scene::face_index(-1, 0, true), 3.9, 1.1},
                                   {Scene::face_index(-1, 0, true), 1.8, 2.2},
                                   {Scene::face_index(-1, 0, true), 3.4, 0.5}};
  std::vector<Eigen::Vector3d> centres;
  for (const auto &c : cases)
    centres.push_back(scene.plant_marker(c.surface, c.u, c.v, 0.04));
  Renderer rend(cam, scene, ro);
  cv::Mat img;
  rend.render(R_WC, p_WC, 0, img);
  for (size_t i = 0; i < centres.size(); ++i) {
    Eigen::Vector2d uv;
    ASSERT_TRUE(cam.project(R_WC.transpose() * (centres[i] - p_WC), uv));
    ASSERT_TRUE(cam.in_image(uv, 30)) << "marker " << i << " at " << uv.transpose();
    const double r_px = 0.04 / (R_WC.transpose() * (centres[i] - p_WC)).z() * cam.fu();
    const Eigen::Vector2d got = dark_centroid(img, uv, 1.5 * r_px);
    std::cout << "[ measured ] marker " << i << " at (" << uv.transpose() << ") radius " << r_px
              << " px: drawn centroid off by " << (got - uv).norm() << " px\n";
    EXPECT_LT((got - uv).norm(), 0.25) << "marker " << i;
  }
}

TEST(SimRender, KltTracksRenderedEurocStretch) {
  SimOptions opt;
  std::string which = "builtin";
  if (ovtest::have_shared_data()) {
    opt.gt_file = ovtest::shared_data() + "/euroc_groundtruth/V1_03_difficult.txt";
    opt.start_s = 40.0;
    which = "V1_03_difficult from 40 s";
  } else {
    std::cout << "[ note ] ../shared/data absent: tracking the built-in trajectory instead of V1_03\n";
  }
  opt.duration_s = 4.0;
  const auto traj = make_trajectory(opt);
  const Scene scene = make_scene(*traj, opt);
  CameraModel cam(opt.cam);
  Renderer rend(cam, scene, opt.render);

  // A front end as a VIO runs it: 200 points, Shi-Tomasi replenishment away from live tracks,
  // 21x21 pyramidal LK over 3 levels with a forward-backward check.
  const int target = 200;
  std::vector<cv::Point2f> pts;
  std::vector<int> age;
  std::vector<double> tracked_per_frame, lengths;
  cv::Mat prev, img;
  double render_s = 0.0;
  int frames = 0;
  for (int64_t t = traj->t_begin_ns(); t <= traj->t_end_ns(); t += 50000000, ++frames) {
    Eigen::Matrix3d R_WC;
    Eigen::Vector3d p_WC;
    camera_pose(traj->sample(t), opt.cam.T_BC, R_WC, p_WC);
    const auto r0 = std::chrono::steady_clock::now();
    rend.render(R_WC, p_WC, frames, img);
    render_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - r0).count();
    if (!pts.empty()) {
      std::vector<cv::Point2f> next, back;
      std::vector<uchar> st, st2;
      std::vector<float> err;
      const cv::Size win(21, 21);
      const cv::TermCriteria tc(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
      cv::calcOpticalFlowPyrLK(prev, img, pts, next, st, err, win, 2, tc);
      cv::calcOpticalFlowPyrLK(img, prev, next, back, st2, err, win, 2, tc);
      std::vector<cv::Point2f> kept;
      std::vector<int> kept_age;
      for (size_t i = 0; i < pts.size(); ++i) {
        const bool ok = st[i] && st2[i] && cv::norm(back[i] - pts[i]) < 0.5 && next[i].x >= 0 && next[i].y >= 0 &&
                        next[i].x < img.cols && next[i].y < img.rows;
        if (ok) {
          kept.push_back(next[i]);
          kept_age.push_back(age[i] + 1);
        } else {
          lengths.push_back(age[i]);
        }
      }
      tracked_per_frame.push_back(static_cast<double>(kept.size()));
      pts = kept;
      age = kept_age;
    }
    if (static_cast<int>(pts.size()) < target) {
      cv::Mat mask(img.size(), CV_8U, cv::Scalar(255));
      for (const auto &p : pts)
        cv::circle(mask, p, 10, cv::Scalar(0), cv::FILLED);
      std::vector<cv::Point2f> fresh;
      cv::goodFeaturesToTrack(img, fresh, target - static_cast<int>(pts.size()), 0.01, 10, mask, 7);
      for (const auto &p : fresh) {
        pts.push_back(p);
        age.push_back(1);
      }
    }
    prev = img.clone();
  }
  for (int a : age)
    lengths.push_back(a);
  // A track is a feature observed in at least two frames (what a filter can use); detections lost at their
  // first tracking attempt are counted separately.
  std::vector<double> tracks;
  for (double l : lengths)
    if (l >= 2)
      tracks.push_back(l);
  const double med_tracked = median(tracked_per_frame), med_len = median(tracks), med_all = median(lengths);
  std::cout << "[ measured ] " << which << ": " << frames << " frames, median tracked " << med_tracked
            << " points/frame, median track length " << med_len << " frames (" << tracks.size() << " tracks; "
            << lengths.size() - tracks.size() << " detections lost at once; median over all " << med_all << "), render "
            << frames / render_s << " frames/s\n";
  EXPECT_GE(med_tracked, 150.0);
  EXPECT_GE(med_len, 10.0);
}
