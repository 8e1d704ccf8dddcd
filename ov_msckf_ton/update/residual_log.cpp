#include "ov_msckf_ton/update/residual_log.h"
#include "ov_core/types/errors.h"

#include <Eigen/Geometry>

#include <algorithm>

namespace ovton::msckf {

ovton::core::CalibrationLogRow calibration_row(const State &state, const std::vector<ResidualRecord> &records) {
  ovton::core::CalibrationLogRow c;
  for (const ResidualRecord &r : records) {
    c.update_id = r.update_id;
    c.t_cam_ns = std::max(c.t_cam_ns, r.t_cam_ns);
  }
  const CalibState &k = state.calib;
  c.estimated = (k.extrinsics_index >= 0 ? c.kExtrinsics : 0) | (k.intrinsics_index >= 0 ? c.kIntrinsics : 0) |
                (k.readout_index >= 0 ? c.kReadout : 0) | (k.imu_intrinsics_index >= 0 ? c.kImuIntrinsics : 0);
  c.td_s = state.td;
  for (int i = 0; i < 9; ++i) {
    c.R_BC[i] = k.R_BC(i / 3, i % 3);
    c.D_w[i] = k.D_w(i / 3, i % 3);
    c.D_a[i] = k.D_a(i / 3, i % 3);
  }
  for (int i = 0; i < 3; ++i) {
    c.p_BC[i] = k.p_BC(i);
    c.b_g[i] = state.imu.bg(i);
    c.b_a[i] = state.imu.ba(i);
  }
  for (int i = 0; i < 8; ++i)
    c.intrinsics[i] = k.intrinsics(i);
  c.readout_s = k.readout_s;
  c.has_state = true;
  c.t_imu_ns = state.t_imu_ns;
  const Eigen::Quaterniond q(state.imu.R);
  const double qs[4] = {q.w(), q.x(), q.y(), q.z()};
  for (int i = 0; i < 4; ++i)
    c.q_WB[i] = qs[i];
  for (int i = 0; i < 3; ++i)
    c.v_W[i] = state.imu.v(i);
  return c;
}

ResidualLogWriter::ResidualLogWriter(const std::string &path)
    : path_(path), calib_path_(ovton::core::calibration_log_path(path)), out_(path, std::ios::trunc),
      calib_out_(calib_path_, std::ios::trunc) {
  if (!out_)
    throw ovton::core::DataError(path, "cannot open the residual log for writing");
  if (!calib_out_)
    throw ovton::core::DataError(calib_path_, "cannot open the calibration log for writing");
  out_ << header() << '\n';
  calib_out_ << ovton::core::calibration_log_header(true) << '\n';
  out_.flush();
  calib_out_.flush();
  if (!out_ || !calib_out_)
    throw ovton::core::DataError(path, "cannot write the residual or calibration log header");
}

void ResidualLogWriter::write(const std::vector<ResidualRecord> &records, const State &state) {
  write(records);
  if (records.empty())
    return;
  calib_out_ << ovton::core::format_calibration_row(calibration_row(state, records)) << '\n';
  calib_out_.flush();
  if (!calib_out_)
    throw ovton::core::DataError(calib_path_, "write failed (disk full?)");
}

std::ofstream &ResidualLogWriter::stream_of_camera(int cam) {
  if (cam <= 0)
    return out_;
  if (more_out_.size() < static_cast<size_t>(cam))
    more_out_.resize(static_cast<size_t>(cam));
  std::unique_ptr<std::ofstream> &o = more_out_[static_cast<size_t>(cam - 1)];
  if (!o) {
    const std::string p = ovton::core::residual_log_path_of_camera(path_, cam);
    o = std::make_unique<std::ofstream>(p, std::ios::trunc);
    if (!*o || !(*o << header() << '\n'))
      throw ovton::core::DataError(p, "cannot open camera " + std::to_string(cam) + "'s residual log for writing");
  }
  return *o;
}

std::vector<std::string> ResidualLogWriter::camera_paths() const {
  std::vector<std::string> out;
  for (size_t k = 0; k < more_out_.size(); ++k)
    if (more_out_[k])
      out.push_back(ovton::core::residual_log_path_of_camera(path_, static_cast<int>(k + 1)));
  return out;
}

void ResidualLogWriter::write(const std::vector<ResidualRecord> &records) {
  for (const ResidualRecord &r : records)
    stream_of_camera(r.cam) << format(r) << '\n';
  out_.flush();
  for (auto &o : more_out_)
    if (o)
      o->flush();
  const bool ok = out_ && std::all_of(more_out_.begin(), more_out_.end(), [](const auto &o) { return !o || *o; });
  if (!ok)
    throw ovton::core::DataError(path_, "write failed after " + std::to_string(rows_) + " rows (disk full?)");
  rows_ += records.size();
}

} // namespace ovton::msckf
