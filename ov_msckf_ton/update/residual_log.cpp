#include "ov_msckf_ton/update/residual_log.h"
#include "ov_core/types/errors.h"

#include <cmath>
#include <cstdio>
#include <functional>

namespace ov_msckf_ton {

namespace {

void put_int(std::string &s, long long v) {
  s += std::to_string(v);
}
void put_uint(std::string &s, unsigned long long v) {
  s += std::to_string(v);
}
/// 10 significant digits: enough for sub-micropixel residuals and nanosecond-level offsets in seconds.
void put_double(std::string &s, double v) {
  if (std::isnan(v)) {
    s += "nan";
    return;
  }
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.10g", v);
  s += buf;
}

struct Column {
  const char *name;
  std::function<void(std::string &, const ResidualRecord &)> put;
};

#define OVTON_COL_I(field)                                                                                             \
  {                                                                                                                    \
#field, [](std::string & s, const ResidualRecord &r) { put_int(s, r.field); }                                      \
  }
#define OVTON_COL_U(field)                                                                                             \
  {                                                                                                                    \
#field, [](std::string & s, const ResidualRecord &r) { put_uint(s, r.field); }                                     \
  }
#define OVTON_COL_D(field)                                                                                             \
  {                                                                                                                    \
#field, [](std::string & s, const ResidualRecord &r) { put_double(s, r.field); }                                   \
  }

/// The column order of the file. The diagnose tool reads columns by header name, so appending is always safe.
const std::vector<Column> &columns() {
  static const std::vector<Column> cols = {
      OVTON_COL_U(update_id),
      OVTON_COL_I(t_cam_ns),
      OVTON_COL_U(feature_id),
      OVTON_COL_I(obs_index),
      OVTON_COL_I(track_length),
      OVTON_COL_D(res_u_px),
      OVTON_COL_D(res_v_px),
      OVTON_COL_D(u_px),
      OVTON_COL_D(v_px),
      OVTON_COL_D(vel_u_px_s),
      OVTON_COL_D(vel_v_px_s),
      OVTON_COL_I(vel_source),
      OVTON_COL_D(depth_m),
      OVTON_COL_D(radius_norm),
      OVTON_COL_D(w_x),
      OVTON_COL_D(w_y),
      OVTON_COL_D(w_z),
      OVTON_COL_D(td_s),
      OVTON_COL_D(chi2),
      OVTON_COL_D(chi2_threshold),
      OVTON_COL_I(accepted),
      {"status", [](std::string &s, const ResidualRecord &r) { put_int(s, static_cast<int>(r.status)); }},
      OVTON_COL_I(td_column),
      OVTON_COL_D(x_norm),
      OVTON_COL_D(y_norm),
      OVTON_COL_I(w_valid),
      OVTON_COL_D(td_ref_s),
  };
  return cols;
}

#undef OVTON_COL_I
#undef OVTON_COL_U
#undef OVTON_COL_D

} // namespace

std::string ResidualLogWriter::header() {
  std::string s;
  for (const Column &c : columns()) {
    if (!s.empty())
      s += ',';
    s += c.name;
  }
  return s;
}

std::string ResidualLogWriter::format(const ResidualRecord &r) {
  std::string s;
  s.reserve(256);
  bool first = true;
  for (const Column &c : columns()) {
    if (!first)
      s += ',';
    first = false;
    c.put(s, r);
  }
  return s;
}

ResidualLogWriter::ResidualLogWriter(const std::string &path) : path_(path), out_(path, std::ios::trunc) {
  if (!out_)
    throw ov_core::DataError(path, "cannot open the residual log for writing");
  out_ << header() << '\n';
  out_.flush();
  if (!out_)
    throw ov_core::DataError(path, "cannot write the residual log header");
}

void ResidualLogWriter::write(const std::vector<ResidualRecord> &records) {
  for (const ResidualRecord &r : records)
    out_ << format(r) << '\n';
  out_.flush();
  if (!out_)
    throw ov_core::DataError(path_, "write failed after " + std::to_string(rows_) + " rows (disk full?)");
  rows_ += records.size();
}

} // namespace ov_msckf_ton
