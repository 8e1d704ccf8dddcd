// KLT front end and feature database: synthetic image pairs with known motion, planted outliers, grid coverage,
// velocity bookkeeping, and the real (still) EuRoC micro sequence.
#include "ov_core/cam/camera_model.h"
#include "ov_core/io/dataset.h"
#include "ov_core/track/feature_database.h"
#include "ov_core/track/track_klt.h"
#include "ov_core/types/errors.h"
#include "ov_sim/euroc_calib.h"
#include "test_util.h"
#include "track_test_util.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>

using namespace ovton::core;

namespace {

constexpr int kW = ovtest::kTrackW, kH = ovtest::kTrackH;
using ovtest::pinhole_calib;
using ovtest::random_texture;
constexpr int64_t kT0 = 1403715273262142976LL; // a real EuRoC stamp: large enough to break double-keyed code
constexpr int64_t kDt = 50000000LL;            // 20 Hz

/// The centre kW x kH crop of `img`, so that warps of a larger texture have no border artefacts.
cv::Mat centre_crop(const cv::Mat &img) {
  return img(cv::Rect((img.cols - kW) / 2, (img.rows - kH) / 2, kW, kH)).clone();
}

std::map<size_t, Eigen::Vector2d> by_id(const std::vector<TrackedFeature> &f) {
  std::map<size_t, Eigen::Vector2d> m;
  for (const auto &t : f)
    m[t.id] = t.uv;
  return m;
}

double median(std::vector<double> v) {
  if (v.empty())
    return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

} // namespace

// ---------------------------------------------------------------------------------------------------------------
// FeatureDatabase

TEST(FeatureDatabase, VelocityIsDifferenceOverStampDifferenceAndFirstIsInvalid) {
  FeatureDatabase db;
  const Eigen::Vector2d uv0(100.25, 200.5), uv1(101.0, 199.75), uv2(103.5, 199.0);
  const Eigen::Vector2d xy0(0.1, -0.2), xy1(0.1015, -0.2012), xy2(0.105, -0.203);
  // Uneven spacing (a dropped frame) must give the velocity over the real interval.
  const int64_t t0 = kT0, t1 = kT0 + kDt, t2 = kT0 + 3 * kDt + 7;
  db.add_observation(7, t0, uv0, xy0);
  db.add_observation(7, t1, uv1, xy1);
  db.add_observation(7, t2, uv2, xy2);

  const Feature *f = db.get(7);
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(f->obs.size(), 3u);
  EXPECT_FALSE(f->obs[0].vel_valid);
  EXPECT_EQ(f->obs[0].vel_uv, Eigen::Vector2d::Zero());
  const double dt1 = static_cast<double>(t1 - t0) * 1e-9, dt2 = static_cast<double>(t2 - t1) * 1e-9;
  EXPECT_TRUE(f->obs[1].vel_valid);
  EXPECT_TRUE(f->obs[2].vel_valid);
  for (int k = 0; k < 2; ++k) {
    EXPECT_DOUBLE_EQ(f->obs[1].vel_uv(k), (uv1(k) - uv0(k)) / dt1);
    EXPECT_DOUBLE_EQ(f->obs[1].vel_xy(k), (xy1(k) - xy0(k)) / dt1);
    EXPECT_DOUBLE_EQ(f->obs[2].vel_uv(k), (uv2(k) - uv1(k)) / dt2);
    EXPECT_DOUBLE_EQ(f->obs[2].vel_xy(k), (xy2(k) - xy1(k)) / dt2);
  }
  // 0.75 px in 50 ms = 15 px/s: the stamp difference is taken in int64 before converting.
  EXPECT_NEAR(f->obs[1].vel_uv.x(), 15.0, 1e-9);
  EXPECT_EQ(f->at(t1), &f->obs[1]);
  EXPECT_EQ(f->at(t1 + 1), nullptr);
}

TEST(FeatureDatabase, RejectsNonIncreasingStampsAndNonFiniteCoordinates) {
  FeatureDatabase db;
  db.add_observation(1, kT0, Eigen::Vector2d(1, 2), Eigen::Vector2d(0, 0));
  EXPECT_THROW(db.add_observation(1, kT0, Eigen::Vector2d(1, 2), Eigen::Vector2d(0, 0)), UsageError);
  EXPECT_THROW(db.add_observation(1, kT0 - 1, Eigen::Vector2d(1, 2), Eigen::Vector2d(0, 0)), UsageError);
  EXPECT_THROW(db.add_observation(2, kT0, Eigen::Vector2d(NAN, 2), Eigen::Vector2d(0, 0)), UsageError);
  EXPECT_EQ(db.size(), 1u);
  EXPECT_EQ(db.num_observations(), 1u);
}

TEST(FeatureDatabase, LostAndOldQueriesAndCleanup) {
  FeatureDatabase db;
  const Eigen::Vector2d z = Eigen::Vector2d::Zero();
  // Frames 0..4. Feature 1: frames 0-4. Feature 2: 0-2 (lost at 3). Feature 3: 2-4. Feature 4: 1-3 (lost at 4).
  auto t = [](int k) { return kT0 + k * kDt; };
  for (int k = 0; k <= 4; ++k) {
    std::vector<TrackedFeature> frame;
    auto add = [&](size_t id) { frame.push_back({id, Eigen::Vector2d(10.0 * id + k, 5.0), z}); };
    add(1);
    if (k <= 2)
      add(2);
    if (k >= 2)
      add(3);
    if (k >= 1 && k <= 3)
      add(4);
    db.add_frame(t(k), frame);
  }
  EXPECT_EQ(db.size(), 4u);
  EXPECT_EQ(db.num_observations(), 5u + 3u + 3u + 3u);

  std::vector<const Feature *> out;
  db.lost_features(t(4), out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0]->id, 2u); // sorted by id
  EXPECT_EQ(out[1]->id, 4u);

  db.features_older_than(t(1), out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0]->id, 1u);
  EXPECT_EQ(out[1]->id, 2u);
  db.features_older_than(t(2), out);
  EXPECT_EQ(out.size(), 3u); // 1, 2, 4

  db.features_observed_at(t(3), out);
  ASSERT_EQ(out.size(), 3u); // 1, 3, 4
  EXPECT_EQ(out[1]->id, 3u);

  // A stamp one nanosecond off matches nothing: no double equality anywhere.
  db.features_observed_at(t(3) + 1, out);
  EXPECT_TRUE(out.empty());

  EXPECT_TRUE(db.remove(4));
  EXPECT_FALSE(db.remove(4));
  EXPECT_EQ(db.get(4), nullptr);

  // Drop frames 0-2: feature 2 has nothing left and disappears; feature 1 keeps frames 3-4 with valid velocity.
  db.remove_observations_older_than(t(3));
  EXPECT_EQ(db.size(), 2u);
  EXPECT_EQ(db.get(2), nullptr);
  ASSERT_NE(db.get(1), nullptr);
  EXPECT_EQ(db.get(1)->obs.size(), 2u);
  EXPECT_EQ(db.get(1)->oldest().t_cam_ns, t(3));
  EXPECT_TRUE(db.get(1)->oldest().vel_valid);
  EXPECT_EQ(db.get(3)->obs.size(), 2u);

  db.remove_observations_at(t(4));
  EXPECT_EQ(db.get(1)->obs.size(), 1u);
  EXPECT_EQ(db.get(1)->newest().t_cam_ns, t(3));
  db.remove_observations_at(t(3));
  EXPECT_EQ(db.size(), 0u);
}

TEST(FeatureDatabase, TracksWithinReservedCapacityDoNotReallocate) {
  FeatureDatabase db(16);
  db.add_observation(3, kT0, Eigen::Vector2d(1, 1), Eigen::Vector2d(0, 0));
  const FeatureObservation *data = db.get(3)->obs.data();
  for (int k = 1; k < 16; ++k)
    db.add_observation(3, kT0 + k * kDt, Eigen::Vector2d(1, 1), Eigen::Vector2d(0, 0));
  EXPECT_EQ(db.get(3)->obs.data(), data);
  // The sliding window's cleanup erases from the front and keeps the buffer.
  db.remove_observations_older_than(kT0 + 10 * kDt);
  db.add_observation(3, kT0 + 20 * kDt, Eigen::Vector2d(1, 1), Eigen::Vector2d(0, 0));
  EXPECT_EQ(db.get(3)->obs.data(), data);
}

// ---------------------------------------------------------------------------------------------------------------
// TrackKLT on synthetic images

TEST(TrackKLT, SubPixelShiftIsRecoveredWithinATenthOfAPixel) {
  const cv::Mat tex = random_texture(kW + 100, kH + 100, 42);
  const double sx = 2.7, sy = -1.3;
  const cv::Mat A = (cv::Mat_<double>(2, 3) << 1, 0, sx, 0, 1, sy);
  cv::Mat shifted;
  cv::warpAffine(tex, shifted, A, tex.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  const cv::Mat img0 = centre_crop(tex), img1 = centre_crop(shifted);

  for (bool fb : {false, true}) {
    for (ImageEqualization eq : {ImageEqualization::None, ImageEqualization::Histogram}) {
      SCOPED_TRACE(std::string("forward_backward=") + (fb ? "on" : "off") +
                   " equalization=" + (eq == ImageEqualization::None ? "none" : "histogram"));
      TrackKLTOptions opt;
      opt.forward_backward = fb;
      opt.equalization = eq;
      TrackKLT trk(CameraModel(pinhole_calib()), opt);
      const auto f0 = by_id(trk.track(kT0, img0));
      ASSERT_EQ(f0.size(), 200u);
      const auto f1 = by_id(trk.track(kT0 + kDt, img1));
      int common = 0;
      double worst = 0;
      for (const auto &[id, uv1] : f1) {
        const auto it = f0.find(id);
        if (it == f0.end())
          continue;
        ++common;
        const double err = (uv1 - it->second - Eigen::Vector2d(sx, sy)).norm();
        // Where the LK window hangs over the image border it sees padding, which no shift explains.
        const int hw = opt.win_size / 2 + 1; // whole pixels: the half window, rounded down
        const bool inside = uv1.x() >= hw && uv1.y() >= hw && uv1.x() <= kW - 1 - hw && uv1.y() <= kH - 1 - hw;
        if (inside) {
          worst = std::max(worst, err);
          EXPECT_LT(err, 0.1) << "feature " << id << " at " << it->second.transpose();
        } else {
          EXPECT_LT(err, 0.3) << "feature " << id << " at " << it->second.transpose();
        }
      }
      // Features near the border may leave the image; nothing else has a reason to be lost.
      EXPECT_GE(common, 190);
      EXPECT_EQ(trk.last_stats().num_ransac_rejected, 0);
      std::printf("[ shift    ] fb=%d eq=%d: %d tracks, worst error (window inside) %.4f px\n", fb,
                  static_cast<int>(eq), common, worst);
    }
  }
}

TEST(TrackKLT, GridDetectionSpreadsFeaturesOverCellsWithMinimumDistance) {
  TrackKLTOptions opt; // 8 x 5 cells, 200 features: 5 per cell
  TrackKLT trk(CameraModel(pinhole_calib()), opt);
  const auto &f = trk.track(kT0, random_texture(kW, kH, 7));
  ASSERT_EQ(f.size(), 200u);
  std::vector<int> per_cell(40, 0);
  for (const auto &t : f)
    ++per_cell[static_cast<int>(t.uv.y() * 5 / kH) * 8 + static_cast<int>(t.uv.x() * 8 / kW)];
  for (int c = 0; c < 40; ++c)
    EXPECT_EQ(per_cell[c], 5) << "cell " << c;
  double min_dist = 1e9;
  for (size_t i = 0; i < f.size(); ++i)
    for (size_t j = i + 1; j < f.size(); ++j)
      min_dist = std::min(min_dist, (f[i].uv - f[j].uv).norm());
  EXPECT_GT(min_dist, opt.min_px_dist);
  std::vector<size_t> ids;
  for (const auto &t : f)
    ids.push_back(t.id);
  std::sort(ids.begin(), ids.end());
  EXPECT_EQ(std::unique(ids.begin(), ids.end()), ids.end());
}

TEST(TrackKLT, TexturelessCellsLeaveTheirShareToTexturedOnes) {
  cv::Mat img = random_texture(kW, kH, 8);
  img(cv::Rect(0, 0, kW / 2, kH)).setTo(cv::Scalar(90)); // left four columns of cells: flat
  TrackKLTOptions opt;
  opt.equalization = ImageEqualization::None;
  TrackKLT trk(CameraModel(pinhole_calib()), opt);
  const auto &f = trk.track(kT0, img);
  std::vector<int> per_cell(40, 0);
  for (const auto &t : f) {
    EXPECT_GE(t.uv.x(), kW / 2 - 3);
    ++per_cell[static_cast<int>(t.uv.y() * 5 / kH) * 8 + static_cast<int>(t.uv.x() * 8 / kW)];
  }
  for (int c = 0; c < 40; ++c)
    EXPECT_LE(per_cell[c], 10) << "cell " << c; // at most twice the equal share
  EXPECT_GE(f.size(), 190u);
}

TEST(TrackKLT, RansacDropsPlantedOutliers) {
  // Camera translating along x over a scene whose inverse depth is not affine in the image, so no homography
  // explains the flow and the fundamental matrix is unique: every inlier moves horizontally, by 2 to 8 px.
  // Inside one rectangle the image is also shifted 8 px down: those tracks are wrong matches for the rigid scene.
  const cv::Mat tex = random_texture(kW, kH, 11);
  const cv::Rect patch(400, 140, 240, 200);
  const double patch_dy = 8.0;
  cv::Mat map_x(kH, kW, CV_32FC1), map_y(kH, kW, CV_32FC1);
  auto flow_x = [](double u, double v) {
    const double a = (u - kW / 2.0) / (kW / 2.0), b = (v - kH / 2.0) / (kH / 2.0);
    return 2.0 + 4.0 * a * a + 2.0 * b * b;
  };
  for (int v = 0; v < kH; ++v)
    for (int u = 0; u < kW; ++u) {
      map_x.at<float>(v, u) = static_cast<float>(u - flow_x(u, v));
      map_y.at<float>(v, u) = static_cast<float>(patch.contains(cv::Point(u, v)) ? v - patch_dy : v);
    }
  cv::Mat img1;
  cv::remap(tex, img1, map_x, map_y, cv::INTER_CUBIC, cv::BORDER_REFLECT);
  const cv::Rect inner(patch.x + 15, patch.y + 15, patch.width - 30, patch.height - 30 - static_cast<int>(patch_dy));

  for (bool ransac : {false, true}) {
    SCOPED_TRACE(ransac ? "ransac on" : "ransac off");
    TrackKLTOptions opt;
    opt.use_ransac = ransac;
    opt.equalization = ImageEqualization::None;
    TrackKLT trk(CameraModel(pinhole_calib()), opt);
    const auto f0 = by_id(trk.track(kT0, tex));
    const auto f1 = by_id(trk.track(kT0 + kDt, img1));
    int planted = 0, planted_kept = 0, good = 0, good_kept = 0;
    for (const auto &[id, uv0] : f0) {
      const bool in_patch = inner.contains(cv::Point(static_cast<int>(uv0.x()), static_cast<int>(uv0.y())));
      const bool near_patch = (patch + cv::Size(30, 30) - cv::Point(15, 15))
                                  .contains(cv::Point(static_cast<int>(uv0.x()), static_cast<int>(uv0.y())));
      const bool kept = f1.count(id) > 0;
      if (in_patch) {
        ++planted;
        planted_kept += kept;
      } else if (!near_patch && uv0.x() < kW - 20) {
        ++good;
        good_kept += kept;
        if (kept) {
          EXPECT_LT(std::abs(f1.at(id).y() - uv0.y()), 0.2) << "an inlier should move horizontally";
        }
      }
    }
    std::printf("[ ransac   ] ransac=%d: planted outliers %d kept %d, inliers %d kept %d\n", ransac, planted,
                planted_kept, good, good_kept);
    ASSERT_GE(planted, 8);
    if (ransac) {
      EXPECT_EQ(planted_kept, 0);
      EXPECT_GE(trk.last_stats().num_ransac_rejected, planted);
    } else {
      EXPECT_EQ(planted_kept, planted); // LK itself follows the patch: the rejection above is RANSAC's doing
    }
    EXPECT_GE(good_kept, good * 95 / 100);
  }
}

TEST(TrackKLT, RansacFunctionRejectsWrongMatchesInRandomScene) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::normal_distribution<double> N(0.0, 0.2 / 458.0); // 0.2 px noise
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.05, Eigen::Vector3d(0.3, 1, 0.2).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(0.2, 0.05, 0.1);
  Eigen::Matrix3d tx;
  tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  const Eigen::Matrix3d E = tx * R; // x1^T E x0 = 0 for p1 = R p0 + t
  std::vector<cv::Point2f> xy0, xy1;
  std::vector<bool> is_outlier;
  for (int i = 0; i < 200; ++i) {
    // EuRoC-like field of view and depths 2-10 m: a narrow view leaves F (7 dof) loose enough to absorb outliers.
    const double z = 2.0 + 4.0 * (U(rng) + 1);
    const Eigen::Vector3d p0(U(rng) * 0.8 * z, U(rng) * 0.5 * z, z);
    const Eigen::Vector3d p1 = R * p0 + t;
    Eigen::Vector2d a = p0.head<2>() / p0.z(), b = p1.head<2>() / p1.z();
    a += Eigen::Vector2d(N(rng), N(rng));
    b += Eigen::Vector2d(N(rng), N(rng));
    bool outlier = false;
    if (i % 5 == 0) {
      b += Eigen::Vector2d(U(rng), U(rng)).normalized() * (10.0 + 20.0 * (U(rng) + 1)) / 458.0;
      // A wrong match that happens to slide along its epipolar line is undetectable by any two-view test.
      const Eigen::Vector3d l = E * Eigen::Vector3d(a.x(), a.y(), 1);
      outlier = std::abs(l.dot(Eigen::Vector3d(b.x(), b.y(), 1))) / l.head<2>().norm() > 3.0 / 458.0;
    }
    xy0.emplace_back(static_cast<float>(a.x()), static_cast<float>(a.y()));
    xy1.emplace_back(static_cast<float>(b.x()), static_cast<float>(b.y()));
    is_outlier.push_back(outlier);
  }
  std::vector<unsigned char> inl;
  ransac_fundamental(xy0, xy1, 1.0 / 458.0, 0.999, inl);
  ASSERT_EQ(inl.size(), xy0.size());
  int outliers = 0, outliers_kept = 0, inliers = 0, inliers_kept = 0;
  for (size_t i = 0; i < inl.size(); ++i) {
    if (is_outlier[i]) {
      ++outliers;
      outliers_kept += inl[i];
    } else if (i % 5 != 0) {
      ++inliers;
      inliers_kept += inl[i];
    }
  }
  EXPECT_GE(outliers, 30);
  EXPECT_EQ(outliers_kept, 0);
  EXPECT_GE(inliers_kept, inliers * 95 / 100);

  // Too few points to estimate anything: everything is kept rather than everything dropped.
  std::vector<cv::Point2f> few0(xy0.begin(), xy0.begin() + 5), few1(xy1.begin(), xy1.begin() + 5);
  EXPECT_EQ(ransac_fundamental(few0, few1, 1.0 / 458.0, 0.999, inl), 5);
}

TEST(TrackKLT, RejectsBadInputAndOptions) {
  const CameraModel cam(pinhole_calib());
  TrackKLT trk(cam);
  EXPECT_THROW(trk.track(kT0, cv::Mat()), UsageError);
  EXPECT_THROW(trk.track(kT0, cv::Mat(kH, kW, CV_8UC3, cv::Scalar(0))), UsageError);
  EXPECT_THROW(trk.track(kT0, cv::Mat(kH / 2, kW, CV_8UC1, cv::Scalar(0))), UsageError);
  const cv::Mat img = random_texture(kW, kH, 1);
  trk.track(kT0, img);
  EXPECT_THROW(trk.track(kT0, img), UsageError);
  EXPECT_NO_THROW(trk.track(kT0 + 1, img));

  auto bad = [&](auto edit) {
    TrackKLTOptions o;
    edit(o);
    EXPECT_THROW(TrackKLT(cam, o), UsageError);
  };
  bad([](TrackKLTOptions &o) { o.win_size = 20; });
  bad([](TrackKLTOptions &o) { o.num_features = 0; });
  bad([](TrackKLTOptions &o) { o.grid_x = 0; });
  bad([](TrackKLTOptions &o) { o.ransac_px = 0; });
  bad([](TrackKLTOptions &o) { o.pyr_levels = -1; });
}

TEST(TrackKLT, ResetStartsFreshTracksWithNewIds) {
  TrackKLT trk{CameraModel(pinhole_calib())};
  const cv::Mat img = random_texture(kW, kH, 5);
  size_t max_id = 0;
  for (const auto &t : trk.track(kT0, img))
    max_id = std::max(max_id, t.id);
  trk.reset();
  for (const auto &t : trk.track(kT0 + kDt, img))
    EXPECT_GT(t.id, max_id);
}

// ---------------------------------------------------------------------------------------------------------------
// Real EuRoC images: the first 4.75 s of V1_01, before take-off.
//
// The vehicle stands on the ground but is not motionless: the gyro shows bursts of 0.02-0.04 rad/s (1-2 deg/s)
// about the camera's x/y axes on top of its bias, i.e. 10-18 px/s of rotational image flow at f = 458 px. The
// tracker measures that motion, so "median velocity < 2 px/s" holds on the frames where the gyro is quiet, while
// over all frames the median is about 2.4 px/s; the test checks both, and that image speed follows the gyro.

namespace {

/// Mean gyro [rad/s] over the IMU samples in [t0_ns, t1_ns) (EuRoC: camera and IMU clocks agree to < 1 ms).
Eigen::Vector3d mean_gyro(const std::vector<ImuData> &imu, int64_t t0_ns, int64_t t1_ns) {
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  int n = 0;
  for (const ImuData &m : imu)
    if (m.t_imu_ns >= t0_ns && m.t_imu_ns < t1_ns) {
      w += m.wm;
      ++n;
    }
  return n > 0 ? Eigen::Vector3d(w / n) : w;
}

double correlation(const std::vector<double> &a, const std::vector<double> &b) {
  const size_t n = a.size();
  double ma = 0, mb = 0;
  for (size_t i = 0; i < n; ++i) {
    ma += a[i] / n;
    mb += b[i] / n;
  }
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < n; ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

} // namespace

TEST(TrackKLT, EurocStillSequenceKeepsLongStableTracks) {
  const std::string dir = std::string(OVTON_SOURCE_DIR) + "/../shared/data/euroc_v1_01_micro";
  if (!std::filesystem::is_directory(dir + "/mav0/cam0"))
    GTEST_SKIP() << "EuRoC sample not found at " << dir << ": this test needs the real V1_01 micro folder";
  const Dataset ds = load_euroc(dir);
  ASSERT_GE(ds.images.size(), 90u);
  const Eigen::Matrix3d R_CB = ds.cam.T_BC.block<3, 3>(0, 0).transpose();

  TrackKLT trk{CameraModel(ds.cam)};
  FeatureDatabase db;
  int min_count = 1 << 30;
  std::vector<double> frame_speed;         // per frame: median |image velocity| of the tracked features [px/s]
  std::vector<Eigen::Vector2d> frame_gyro; // per frame: mean gyro about the camera x and y axes [rad/s]
  double t_load_ms = 0;
  for (size_t k = 0; k < ds.images.size(); ++k) {
    const ImageEntry &e = ds.images[k];
    const auto t0 = std::chrono::steady_clock::now();
    const cv::Mat gray = cv::imread(e.path, cv::IMREAD_GRAYSCALE);
    t_load_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ASSERT_FALSE(gray.empty()) << e.path;
    const auto &frame = trk.track(e.t_cam_ns, gray);
    db.add_frame(e.t_cam_ns, frame);
    min_count = std::min(min_count, static_cast<int>(frame.size()));
    if (k == 0)
      continue;
    std::vector<double> speeds;
    for (const auto &t : frame) {
      const FeatureObservation &o = db.get(t.id)->newest();
      if (o.vel_valid)
        speeds.push_back(o.vel_uv.norm());
    }
    ASSERT_FALSE(speeds.empty());
    frame_speed.push_back(median(speeds));
    frame_gyro.push_back((R_CB * mean_gyro(ds.imu, ds.images[k - 1].t_cam_ns, e.t_cam_ns)).head<2>());
  }

  // Rotational flow at the image centre predicted by the gyro, against its median over the sequence (the bias).
  std::vector<double> gx, gy;
  for (const auto &g : frame_gyro) {
    gx.push_back(g.x());
    gy.push_back(g.y());
  }
  const Eigen::Vector2d gyro_base(median(gx), median(gy));
  std::vector<double> gyro_flow, quiet_speed;
  for (size_t i = 0; i < frame_gyro.size(); ++i) {
    gyro_flow.push_back(ds.cam.intrinsics(0) * (frame_gyro[i] - gyro_base).norm());
    if (gyro_flow.back() < 1.0)
      quiet_speed.push_back(frame_speed[i]);
  }

  std::vector<double> lengths;
  for (const auto &kv : db.features())
    lengths.push_back(static_cast<double>(kv.second.obs.size()));
  std::vector<const Feature *> alive;
  db.features_observed_at(ds.images.back().t_cam_ns, alive);

  const TrackStatsTotals &tot = trk.totals();
  const double corr = correlation(frame_speed, gyro_flow);
  std::printf("[ euroc    ] %zu frames: min features/frame %d, tracks %zu (alive at end %zu), median track "
              "length %.0f\n",
              ds.images.size(), min_count, db.size(), alive.size(), median(lengths));
  std::printf("[ euroc    ] image speed (median of per-frame medians): all frames %.2f px/s (max %.2f), "
              "%zu gyro-quiet frames %.2f px/s; correlation with gyro flow %.2f\n",
              median(frame_speed), *std::max_element(frame_speed.begin(), frame_speed.end()), quiet_speed.size(),
              median(quiet_speed), corr);
  std::printf("[ euroc    ] ms/frame: imread %.2f | equalize %.2f pyramid %.2f LK %.2f undistort %.3f ransac %.2f "
              "detect %.2f | tracker total %.2f\n",
              t_load_ms / tot.frames, tot.mean(tot.t_equalize_ms), tot.mean(tot.t_pyramid_ms),
              tot.mean(tot.t_tracking_ms), tot.mean(tot.t_undistort_ms), tot.mean(tot.t_ransac_ms),
              tot.mean(tot.t_detection_ms), tot.mean(tot.t_total_ms));

  EXPECT_GE(min_count, 150);
  EXPECT_GE(median(lengths), 20.0);
  ASSERT_GE(quiet_speed.size(), 10u);
  EXPECT_LT(median(quiet_speed), 2.0); // still camera: tracking jitter only
  EXPECT_LT(median(frame_speed), 3.0); // whole sequence, vibration included
  EXPECT_GT(corr, 0.8);                // what the tracker reports as motion is motion
}
