#include "ov_eval/diagnose/residual_design.h"
#include "ov_core/math/so3.h"
#include "ov_eval/diagnose/candidates.h"
#include "ov_eval/diagnose/image_geometry.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <memory>

namespace ovton::eval::diag {

using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

/// Replaces every column x of X, within each track (rows [begin, end) of one cluster), by x − J·(J⁺x): what the
/// track's triangulated point could not absorb. J (2m × 3) is the track's point Jacobian.
void project_out_points(const MatrixXd &J_point, const std::vector<int> &cluster, MatrixXd &X) {
  const Eigen::Index n = X.rows();
  for (Eigen::Index i0 = 0; i0 < n;) {
    Eigen::Index i1 = i0;
    while (i1 < n && cluster[i1] == cluster[i0])
      ++i1;
    // Rank-revealing: under pure rotation (or without parallax) the point's depth changes nothing, J has rank 2, and a
    // plain QR would remove an arbitrary third direction.
    Eigen::ColPivHouseholderQR<MatrixXd> qr(J_point.middleRows(i0, i1 - i0));
    qr.setThreshold(1e-9);
    const MatrixXd Q1 = qr.householderQ() * MatrixXd::Identity(i1 - i0, qr.rank());
    X.middleRows(i0, i1 - i0) -= Q1 * (Q1.transpose() * X.middleRows(i0, i1 - i0));
    i0 = i1;
  }
}

/// Derivative at t of the parabola through (t0, x0), (t1, x1), (t2, x2) (distinct times).
Eigen::Vector2d lagrange_derivative(double t0, double t1, double t2, const Eigen::Vector2d &x0,
                                    const Eigen::Vector2d &x1, const Eigen::Vector2d &x2, double t) {
  const double l0 = ((t - t1) + (t - t2)) / ((t0 - t1) * (t0 - t2));
  const double l1 = ((t - t0) + (t - t2)) / ((t1 - t0) * (t1 - t2));
  const double l2 = ((t - t0) + (t - t1)) / ((t2 - t0) * (t2 - t1));
  return l0 * x0 + l1 * x1 + l2 * x2;
}

/// The residual rows' clusters [s] and the Newey-West lags over them. The residuals of every track an update
/// processes share that update's clone poses, and consecutive updates share most of their clones (the shipped
/// configs' window: 20 clones, a second at 20 Hz), so the rows' errors correlate across tracks and over the window.
/// Clustered per track, the scores would be taken as independent between tracks, which they are not: a short real
/// flight then names a camera-IMU translation its images cannot resolve (docs/diagnose_undeclared.md, "Real data and
/// short flights"). A track belongs to the cluster of its update's time; the lags span the window.
constexpr double kResidualClusterS = 0.25;
constexpr int kResidualHacLags = 4;

} // namespace

Design build_residual_design(const UsedData &data, const DiagnoseOptions &opt, DiagnoseReport &rep) {
  std::unique_ptr<ovton::core::CameraModel> cam;
  if (opt.have_camera)
    cam = std::make_unique<ovton::core::CameraModel>(opt.camera);
  const long n_obs = data.observations;
  const int64_t t_first = data.t_first;
  Design d;
  const Eigen::Index n = 2 * n_obs;
  d.D = MatrixXd::Zero(n, kNumCols);
  d.r.resize(n);
  d.cluster.resize(n);
  d.t_s.resize(n);
  d.region.assign(n, -1);
  d.motion.assign(n, 0.0);
  std::vector<int> track_of(n); // the point projection's groups: one track each
  d.have_velocity = data.use_velocity;
  d.t_mid = 0.5 * rep.duration_s;
  MatrixXd J_point(n, 3); // per track: the point Jacobian (pixels per metre, in the track's first camera frame)
  long rate_rows = 0;
  Eigen::Index i = 0;
  int g = 0;
  for (const auto &kv : data.tracks) {
    const Track &tr = kv.second;
    const size_t m = tr.size();
    bool rates = true, depths = true;
    for (auto *r : tr) {
      rates = rates && r->w_valid;
      depths = depths && std::isfinite(r->depth_m) && r->depth_m > 0;
    }
    // Regressors are built from the filter's PREDICTED observations ẑ = z − r, not from the measured pixels: a
    // measured pixel carries the noise that is also in its residual, and regressing on it fakes effects (an offset of
    // σ²/(Δt·var V) from a velocity, a focal error from a position). ẑ's own error is the triangulated point's
    // J·δp, which the point projection below removes. Velocity: three-point derivative of f·ẑ (exact for a
    // quadratic image track), at every row.
    std::vector<Eigen::Vector2d> xh(m), vel(m, Eigen::Vector2d::Zero());
    std::vector<double> ts(m);
    for (size_t j = 0; j < m; ++j) {
      xh[j] = Eigen::Vector2d(tr[j]->x_norm - tr[j]->res_u_px / rep.fu, tr[j]->y_norm - tr[j]->res_v_px / rep.fv);
      ts[j] = 1e-9 * double(tr[j]->t_cam_ns - t_first);
    }
    for (size_t j = 0; j < m; ++j) {
      if (opt.use_logged_velocity) {
        vel[j] = Eigen::Vector2d(tr[j]->vel_u_px_s, tr[j]->vel_v_px_s);
        continue;
      }
      const size_t a = j == 0 ? 0 : (j + 1 == m ? m - 3 : j - 1); // the three rows around j
      vel[j] = Eigen::Vector2d(rep.fu, rep.fv)
                   .cwiseProduct(lagrange_derivative(ts[a], ts[a + 1], ts[a + 2], xh[a], xh[a + 1], xh[a + 2], ts[j]));
    }
    // Camera rotation along the track (R_C0Cj) from the logged body rates, for the point projection.
    std::vector<Eigen::Matrix3d> R_C0C(m, Eigen::Matrix3d::Identity());
    if (rates && opt.have_camera) {
      const Eigen::Matrix3d R_BC = opt.camera.T_BC.block<3, 3>(0, 0);
      Eigen::Matrix3d R_B0B = Eigen::Matrix3d::Identity();
      for (size_t j = 1; j < m; ++j) {
        const Eigen::Vector3d w0(tr[j - 1]->w_x, tr[j - 1]->w_y, tr[j - 1]->w_z),
            w1(tr[j]->w_x, tr[j]->w_y, tr[j]->w_z);
        R_B0B = R_B0B * ovton::core::so3_exp(0.5 * (w0 + w1) * 1e-9 * double(tr[j]->t_cam_ns - tr[j - 1]->t_cam_ns));
        R_C0C[j] = R_BC.transpose() * R_B0B * R_BC;
      }
    }
    Eigen::Vector3d theta = Eigen::Vector3d::Zero(), w_prev = Eigen::Vector3d::Zero();
    int64_t t_prev = tr.front()->t_cam_ns;
    // The track's update: its newest observation's time (the update processes a track when it ends).
    const int cluster = static_cast<int>(1e-9 * double(tr.back()->t_cam_ns - t_first) / kResidualClusterS);
    for (size_t j = 0; j < m; ++j) {
      const ResidualLogRow *r = tr[j];
      const double t = ts[j];
      const Eigen::Vector2d V = vel[j];
      const double row_frac = (r->v_px - r->res_v_px) / rep.image_height - 0.5;
      const ErrorDirs dirs = error_dirs(cam.get(), xh[j]);
      const Eigen::Vector3d w(r->w_x, r->w_y, r->w_z);
      if (rates) { // trapezoid integral of the body rate since the track's first row
        theta += 0.5 * (w + w_prev) * 1e-9 * double(r->t_cam_ns - t_prev);
        if (j == 0)
          theta.setZero();
        w_prev = w, t_prev = r->t_cam_ns;
      }
      const double inv_z = depths ? 1.0 / r->depth_m : 1.0;
      const Eigen::Matrix<double, 2, 3> B = rot_flow(xh[j].x(), xh[j].y());
      Eigen::Matrix<double, 2, 3> Jpt;
      Jpt << inv_z, 0.0, -xh[j].x() * inv_z, 0.0, inv_z, -xh[j].y() * inv_z;
      Jpt = Jpt * R_C0C[j].transpose(); // a shift of the point, expressed in the track's first camera frame
      for (int a = 0; a < 2; ++a, ++i) {
        const double fa = a == 0 ? rep.fu : rep.fv;
        d.r(i) = a == 0 ? r->res_u_px : r->res_v_px;
        d.cluster[i] = cluster;
        track_of[i] = g;
        d.t_s[i] = t;
        {
          // The predicted pixel's cell of a 3 × 3 grid (width ≈ 2·cu), for the test of unexplained structure.
          const double u = rep.fu * xh[j].x() + rep.cu, v = rep.fv * xh[j].y() + rep.cv;
          const int cx = std::clamp(static_cast<int>(3 * u / std::max(1.0, 2 * rep.cu)), 0, 2);
          const int cy = std::clamp(static_cast<int>(3 * v / std::max(1, rep.image_height)), 0, 2);
          d.region[i] = 3 * cy + cx;
          d.motion[i] = V.norm();
        }
        d.D(i, kV) = V(a);
        d.D(i, kVt) = V(a) * (t - d.t_mid);
        d.D(i, kVrow) = V(a) * row_frac;
        d.D(i, kFocal) = fa * dirs.focal(a);
        d.D(i, kPpU) = a == 0 ? 1.0 : 0.0;
        d.D(i, kPpV) = a == 1 ? 1.0 : 0.0;
        d.D(i, kRadial) = fa * dirs.k1(a);
        const int tb = td_bin(t, rep.duration_s);
        if (tb > 0 && tb < kTdBins - 1)
          d.D(i, kTdBin0 + tb - 1) = V(a);
        // A camera-body translation error δp moves every point by −R_CB·δp in the camera frame: constant there, so
        // only the camera's rotation along the track keeps the point from absorbing it. Needs the depths.
        if (depths)
          d.D(i, kExtTrans0) = -fa * (a == 0 ? inv_z : 0.0), d.D(i, kExtTrans0 + 1) = -fa * (a == 1 ? inv_z : 0.0),
                 d.D(i, kExtTrans0 + 2) = fa * xh[j](a) * inv_z;
        if (rates)
          for (int c = 0; c < 3; ++c)
            for (int q = 0; q < 3; ++q)
              d.D(i, kGyro0 + 3 * c + q) = fa * B(a, c) * theta(q);
        if (rates && cam) // R_CB known: one isotropic scale, M = −s·R_CB
          d.D(i, kGyroScale) = -fa * B.row(a).dot(opt.camera.T_BC.block<3, 3>(0, 0).transpose() * theta);
        J_point.row(i) = fa * Jpt.row(a);
      }
      rate_rows += rates;
    }
    ++g;
  }
  // Point projection: the filter triangulates each track's point from its observations, so whatever a shift of the
  // point can produce (J_point·δp) is absorbed by it and is not in the residual. Only the part of an effect orthogonal
  // to J_point's columns can show: residual and regressors are projected onto that complement (docs/diagnose.md). A
  // constant image shift lies (nearly) in J_point's span: the principal point column is kept raw and is weak.
  {
    std::vector<int> cols;
    for (int c = 0; c < kNumCols; ++c)
      if (c != kPpU && c != kPpV)
        cols.push_back(c);
    MatrixXd X(n, cols.size() + 1);
    for (size_t c = 0; c < cols.size(); ++c)
      X.col(c) = d.D.col(cols[c]);
    X.col(cols.size()) = d.r;
    project_out_points(J_point, track_of, X);
    for (size_t c = 0; c < cols.size(); ++c)
      d.D.col(cols[c]) = X.col(c);
    d.r = X.col(cols.size());
  }
  d.n_clusters = 1 + *std::max_element(d.cluster.begin(), d.cluster.end());
  d.hac_lags = kResidualHacLags;
  d.have_rate = rate_rows >= 0.5 * n_obs;
  {
    std::vector<double> absr(n);
    double ss = 0;
    for (Eigen::Index k = 0; k < n; ++k)
      absr[k] = std::abs(d.r(k)), ss += d.r(k) * d.r(k);
    rep.residual_rms_px = std::sqrt(ss / double(n));
    d.scale = std::max(1e-9, 1.4826 * median(absr));
    rep.robust_sigma_px = d.scale;
  }
  return d;
}

} // namespace ovton::eval::diag
