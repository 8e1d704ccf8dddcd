#include "ov_eval/diagnose/tracks.h"
#include "ov_core/types/errors.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ovton::eval::diag {

UsedData select_data(const ResidualLog &log, const DiagnoseOptions &opt, DiagnoseReport &rep) {
  UsedData data;
  auto &rows = data.rows;
  // Rows with a residual (accepted or gated: a gated feature may be gated precisely because of the missing effect).
  long with_vel = 0;
  for (const auto &r : log.rows) {
    if (r.status == ovton::core::ResidualStatus::TriangulationFailed) {
      ++rep.rows_triangulation_failed;
      continue;
    }
    rows.push_back(&r);
    with_vel += r.vel_source != 0;
  }
  // The time candidates need V; keeping rows without it would make their R² not comparable with the others', so the
  // common sample is the rows with a velocity whenever most rows have one (all but the first of each track).
  data.use_velocity =
      !opt.use_logged_velocity || (!rows.empty() && with_vel >= opt.min_velocity_share * double(rows.size()));
  if (data.use_velocity && opt.use_logged_velocity) {
    std::vector<const ResidualLogRow *> kept;
    for (auto *r : rows)
      if (r->vel_source != 0)
        kept.push_back(r);
    rep.rows_without_velocity = static_cast<long>(rows.size() - kept.size());
    rows.swap(kept);
  }
  // Tracks: one feature in one update. Three rows at least: the velocity is a three-point derivative, and the point
  // projection takes three of the 2m residual components.
  const size_t min_track = 3;
  auto &tracks = data.tracks;
  for (auto *r : rows)
    tracks[{r->update_id, r->feature_id}].push_back(r);
  for (auto it = tracks.begin(); it != tracks.end();)
    it = it->second.size() < min_track ? tracks.erase(it) : std::next(it);
  for (auto &kv : tracks)
    data.observations += static_cast<long>(kv.second.size());
  rep.rows_used = data.observations;
  rep.tracks_used = static_cast<long>(tracks.size());
  if (tracks.empty())
    return data;
  data.t_first = std::numeric_limits<int64_t>::max(), data.t_last = std::numeric_limits<int64_t>::min();
  for (auto &kv : tracks) {
    for (auto *r : kv.second)
      data.t_first = std::min(data.t_first, r->t_cam_ns), data.t_last = std::max(data.t_last, r->t_cam_ns);
    std::sort(kv.second.begin(), kv.second.end(), [](auto *a, auto *b) { return a->t_cam_ns < b->t_cam_ns; });
  }
  rep.duration_s = 1e-9 * double(data.t_last - data.t_first);
  return data;
}

void set_intrinsics(const UsedData &data, const DiagnoseOptions &opt, const std::string &log_file,
                    DiagnoseReport &rep) {
  // The dataset's camera, given, or fitted from the log (u ≈ cu + fu·x near the centre, where distortion is small).
  if (opt.have_camera) {
    rep.fu = opt.camera.intrinsics(0), rep.fv = opt.camera.intrinsics(1);
    rep.cu = opt.camera.intrinsics(2), rep.cv = opt.camera.intrinsics(3);
  } else if (opt.fu > 0 && opt.fv > 0) {
    rep.fu = opt.fu, rep.fv = opt.fv, rep.cu = opt.cu, rep.cv = opt.cv;
  } else {
    rep.intrinsics_fitted = true;
    for (double rmax : {0.3, 1e9}) {
      Eigen::Matrix2d Au = Eigen::Matrix2d::Zero(), Av = Eigen::Matrix2d::Zero();
      Eigen::Vector2d bu = Eigen::Vector2d::Zero(), bv = Eigen::Vector2d::Zero();
      long cnt = 0;
      for (auto *r : data.rows) {
        if (r->radius_norm > rmax)
          continue;
        ++cnt;
        const Eigen::Vector2d hu(1, r->x_norm), hv(1, r->y_norm);
        Au += hu * hu.transpose(), bu += hu * r->u_px;
        Av += hv * hv.transpose(), bv += hv * r->v_px;
      }
      if (cnt < 100 && rmax < 1e9)
        continue;
      const Eigen::Vector2d su = Au.ldlt().solve(bu), sv = Av.ldlt().solve(bv);
      rep.cu = su(0), rep.fu = su(1), rep.cv = sv(0), rep.fv = sv(1);
      break;
    }
    if (!(rep.fu > 0) || !(rep.fv > 0))
      throw ovton::core::DataError(log_file, "cannot fit the focal length from (u_px, x_norm): pass --dataset");
  }
  double vmax = 0;
  for (auto *r : data.rows)
    vmax = std::max(vmax, r->v_px);
  rep.image_height = opt.image_height > 0                       ? opt.image_height
                     : opt.have_camera && opt.camera.height > 0 ? opt.camera.height
                                                                : static_cast<int>(std::ceil(vmax + 0.5));
}

} // namespace ovton::eval::diag
