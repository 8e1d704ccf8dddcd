#include "ov_core/io/residual_log_schema.h"
#include "ov_core/io/csv.h"
#include "ov_core/types/errors.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <type_traits>
#include <variant>

namespace ovton::core {

namespace {

using Row = ResidualLogRow;
/// The row field a column holds; its type says how it is written and read.
using Field = std::variant<int Row::*, int64_t Row::*, uint64_t Row::*, double Row::*, ResidualStatus Row::*>;

/// Required columns must be in a file for it to be read; optional ones (added after the first version, or not needed
/// by any reader yet) keep the row's default when absent.
enum class Read { Required, Optional };
/// Reals that may be "nan": quantities that do not always exist (a failed triangulation's residual, an unknown
/// depth, a chi-square that was never computed). Any other real must be finite.
enum class Nan { Rejected, Allowed };

struct Column {
  const char *name;
  Field field;
  Read read;
  Nan nan = Nan::Rejected;
};

/// The columns in file order. Readers find columns by header name, so appending is always safe.
const std::vector<Column> &columns() {
  static const std::vector<Column> cols = {
      {"update_id", &Row::update_id, Read::Required},
      {"t_cam_ns", &Row::t_cam_ns, Read::Required},
      {"feature_id", &Row::feature_id, Read::Required},
      {"obs_index", &Row::obs_index, Read::Required},
      {"track_length", &Row::track_length, Read::Required},
      {"res_u_px", &Row::res_u_px, Read::Required, Nan::Allowed}, // finite unless status 2: checked per row
      {"res_v_px", &Row::res_v_px, Read::Required, Nan::Allowed},
      {"u_px", &Row::u_px, Read::Required},
      {"v_px", &Row::v_px, Read::Required},
      {"vel_u_px_s", &Row::vel_u_px_s, Read::Required},
      {"vel_v_px_s", &Row::vel_v_px_s, Read::Required},
      {"vel_source", &Row::vel_source, Read::Required},
      {"depth_m", &Row::depth_m, Read::Optional, Nan::Allowed},
      {"radius_norm", &Row::radius_norm, Read::Required},
      {"w_x", &Row::w_x, Read::Required},
      {"w_y", &Row::w_y, Read::Required},
      {"w_z", &Row::w_z, Read::Required},
      {"td_s", &Row::td_s, Read::Required},
      {"chi2", &Row::chi2, Read::Optional, Nan::Allowed},
      {"chi2_threshold", &Row::chi2_threshold, Read::Optional, Nan::Allowed},
      {"accepted", &Row::accepted, Read::Optional},
      {"status", &Row::status, Read::Required},
      {"td_column", &Row::td_column, Read::Optional},
      {"x_norm", &Row::x_norm, Read::Required},
      {"y_norm", &Row::y_norm, Read::Required},
      {"w_valid", &Row::w_valid, Read::Required},
      {"td_ref_s", &Row::td_ref_s, Read::Optional},
  };
  return cols;
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

void put(std::string &s, const Row &r, const Field &field) {
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(r.*member)>;
        if constexpr (std::is_same_v<T, double>)
          put_double(s, r.*member);
        else if constexpr (std::is_same_v<T, ResidualStatus>)
          s += std::to_string(static_cast<int>(r.*member));
        else if constexpr (std::is_same_v<T, uint64_t>)
          s += std::to_string(static_cast<unsigned long long>(r.*member));
        else
          s += std::to_string(static_cast<long long>(r.*member));
      },
      field);
}

/// Like TextTableReader::to_double but lets "nan" through: the writer logs NaN where a quantity does not exist, and
/// the column (or the row's status) decides whether that is allowed.
double parse_number(const TextTableReader &rd, const std::string &field, const std::string &what) {
  if (field.empty())
    rd.fail("empty " + what);
  char *end = nullptr;
  errno = 0;
  const double v = std::strtod(field.c_str(), &end);
  if (*end != '\0')
    rd.fail("bad " + what + " '" + field + "' (expected a number)");
  if (std::isinf(v))
    rd.fail("infinite " + what + " '" + field + "'");
  return v;
}

void get(const TextTableReader &rd, const std::string &text, const Column &c, Row &r) {
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(r.*member)>;
        if constexpr (std::is_same_v<T, double>) {
          r.*member = parse_number(rd, text, c.name);
          if (c.nan == Nan::Rejected && std::isnan(r.*member))
            rd.fail(std::string("NaN ") + c.name);
        } else if constexpr (std::is_same_v<T, ResidualStatus>) {
          const int v = static_cast<int>(rd.to_int64(text, c.name));
          if (v < 0 || v > 2)
            rd.fail("status " + std::to_string(v) + " is not 0 (accepted), 1 (gated) or 2 (triangulation failed)");
          r.*member = static_cast<ResidualStatus>(v);
        } else {
          r.*member = static_cast<T>(rd.to_int64(text, c.name));
        }
      },
      c.field);
}

/// The header: the last non-'#' line the reader skipped before the first data row ("" when none).
std::string header_line(const TextTableReader &rd) {
  for (auto it = rd.comments().rbegin(); it != rd.comments().rend(); ++it)
    if (!it->empty() && (*it)[0] != '#')
      return *it;
  return "";
}

} // namespace

std::string residual_log_header() {
  std::string s;
  for (const Column &c : columns()) {
    if (!s.empty())
      s += ',';
    s += c.name;
  }
  return s;
}

std::string format_residual_row(const ResidualLogRow &r) {
  std::string s;
  s.reserve(256);
  bool first = true;
  for (const Column &c : columns()) {
    if (!first)
      s += ',';
    first = false;
    put(s, r, c.field);
  }
  return s;
}

ResidualLog load_residual_log(const std::string &file) {
  TextTableReader rd(file, ',');
  ResidualLog log;
  log.file = file;
  std::vector<std::string> f;
  bool have_row = rd.next(f);
  const std::string header = header_line(rd);
  if (header.empty())
    throw DataError(file, 1, "no header line: expected the residual log's column names (ovton run --residual-log)");
  const long header_line = have_row ? std::max(1L, rd.line() - 1) : 1L;
  std::map<std::string, size_t> col;
  {
    std::stringstream ss(header);
    std::string name;
    size_t i = 0;
    while (std::getline(ss, name, ',')) {
      name.erase(0, name.find_first_not_of(" \t\r"));
      name.erase(name.find_last_not_of(" \t\r") + 1);
      col[name] = i++;
    }
  }
  // Where each column of the schema is in this file; a row must reach the last required one.
  std::vector<std::pair<const Column *, size_t>> present;
  size_t max_col = 0;
  for (const Column &c : columns()) {
    const auto it = col.find(c.name);
    if (it == col.end()) {
      if (c.read == Read::Required)
        throw DataError(file, header_line,
                        std::string("header has no column '") + c.name + "': not a residual log of this version");
      continue;
    }
    if (c.read == Read::Required)
      max_col = std::max(max_col, it->second);
    present.emplace_back(&c, it->second);
  }
  while (have_row) {
    if (f.size() <= max_col)
      rd.fail("row has " + std::to_string(f.size()) + " fields, the header names " + std::to_string(col.size()));
    ResidualLogRow r;
    r.line = rd.line();
    for (const auto &[c, i] : present)
      if (i < f.size())
        get(rd, f[i], *c, r);
    if (r.status != ResidualStatus::TriangulationFailed && (std::isnan(r.res_u_px) || std::isnan(r.res_v_px)))
      rd.fail("NaN residual in a row whose status (" + std::to_string(static_cast<int>(r.status)) +
              ") says it was computed");
    log.rows.push_back(r);
    have_row = rd.next(f);
  }
  return log;
}

} // namespace ovton::core

namespace ovton::core {

namespace {

using CRow = CalibrationLogRow;

/// The calibration log's real columns: name prefix, the row's array and its length (name_i, or name_rc for 3 × 3).
struct CalibArray {
  const char *name;
  double *(*at)(CRow &);
  int n;
};
const std::vector<CalibArray> &calib_arrays() {
  static const std::vector<CalibArray> a = {
      {"td_s", [](CRow &r) { return &r.td_s; }, 1},
      {"R_BC", [](CRow &r) { return r.R_BC; }, 9},
      {"p_BC", [](CRow &r) { return r.p_BC; }, 3},
      {"intr", [](CRow &r) { return r.intrinsics; }, 8},
      {"readout_s", [](CRow &r) { return &r.readout_s; }, 1},
      {"D_w", [](CRow &r) { return r.D_w; }, 9},
      {"D_a", [](CRow &r) { return r.D_a; }, 9},
      {"b_g", [](CRow &r) { return r.b_g; }, 3},
      {"b_a", [](CRow &r) { return r.b_a; }, 3},
  };
  return a;
}

std::vector<std::string> calib_real_names() {
  std::vector<std::string> names;
  for (const CalibArray &a : calib_arrays())
    for (int i = 0; i < a.n; ++i)
      names.push_back(a.n == 1   ? std::string(a.name)
                      : a.n == 9 ? std::string(a.name) + "_" + std::to_string(i / 3) + std::to_string(i % 3)
                                 : std::string(a.name) + "_" + std::to_string(i));
  return names;
}

/// The IMU state's columns after the calibration's (older logs end before them).
const char *const kStateColumns = ",t_imu_ns,q_WB_w,q_WB_x,q_WB_y,q_WB_z,v_W_0,v_W_1,v_W_2";
constexpr size_t kStateCount = 8;

} // namespace

namespace {

/// The path split before its extension (none when the last component has no dot after its first character).
std::pair<std::string, std::string> stem_and_extension(const std::string &path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash + 1);
  return has_ext ? std::make_pair(path.substr(0, dot), path.substr(dot)) : std::make_pair(path, std::string());
}

} // namespace

std::string calibration_log_path(const std::string &residual_log) {
  return stem_and_extension(residual_log).first + "_calib.csv";
}

std::string residual_log_path_of_camera(const std::string &path, int cam) {
  if (cam == 0)
    return path;
  const auto [stem, ext] = stem_and_extension(path);
  return stem + "_cam" + std::to_string(cam) + ext;
}

int camera_of_residual_log(const std::string &path) {
  const std::string stem = stem_and_extension(path).first;
  const size_t at = stem.rfind("_cam");
  if (at == std::string::npos || at + 4 >= stem.size() || stem.find('/', at) != std::string::npos)
    return 0;
  int cam = 0;
  for (size_t i = at + 4; i < stem.size(); ++i) {
    if (stem[i] < '0' || stem[i] > '9' || cam > 1000)
      return 0;
    cam = 10 * cam + (stem[i] - '0');
  }
  return cam;
}

std::string calibration_log_header(bool with_state) {
  std::string s = "update_id,t_cam_ns,estimated";
  for (const std::string &n : calib_real_names())
    s += "," + n;
  return with_state ? s + kStateColumns : s;
}

std::string format_calibration_row(const CalibrationLogRow &r) {
  std::string s = std::to_string(static_cast<unsigned long long>(r.update_id)) + "," +
                  std::to_string(static_cast<long long>(r.t_cam_ns)) + "," + std::to_string(r.estimated);
  CRow copy = r;
  for (const CalibArray &a : calib_arrays())
    for (int i = 0; i < a.n; ++i) {
      s += ',';
      put_double(s, a.at(copy)[i]);
    }
  if (!r.has_state)
    return s;
  s += ',' + std::to_string(static_cast<long long>(r.t_imu_ns));
  for (double v : {r.q_WB[0], r.q_WB[1], r.q_WB[2], r.q_WB[3], r.v_W[0], r.v_W[1], r.v_W[2]}) {
    s += ',';
    put_double(s, v);
  }
  return s;
}

std::vector<CalibrationLogRow> load_calibration_log(const std::string &file) {
  TextTableReader rd(file, ',');
  std::vector<std::string> f;
  bool have_row = rd.next(f);
  std::string header = header_line(rd);
  while (!header.empty() && (header.back() == '\r' || header.back() == ' '))
    header.pop_back();
  const bool with_state = header == calibration_log_header(true);
  if (!with_state && header != calibration_log_header(false))
    throw DataError(file, 1, "header is not the calibration log's (ovton run --residual-log writes it beside the log)");
  const size_t n_cols = 3 + calib_real_names().size() + (with_state ? kStateCount : 0);
  std::vector<CalibrationLogRow> rows;
  while (have_row) {
    if (f.size() != n_cols)
      rd.fail("row has " + std::to_string(f.size()) + " fields, the header names " + std::to_string(n_cols));
    CRow r;
    r.line = rd.line();
    r.update_id = static_cast<uint64_t>(rd.to_int64(f[0], "update_id"));
    r.t_cam_ns = rd.to_int64(f[1], "t_cam_ns");
    r.estimated = static_cast<int>(rd.to_int64(f[2], "estimated"));
    size_t k = 3;
    for (const CalibArray &a : calib_arrays())
      for (int i = 0; i < a.n; ++i, ++k) {
        const double v = parse_number(rd, f[k], a.name);
        if (!std::isfinite(v))
          rd.fail(std::string("NaN ") + a.name);
        a.at(r)[i] = v;
      }
    if (with_state) {
      r.has_state = true;
      r.t_imu_ns = rd.to_int64(f[k++], "t_imu_ns");
      double *dst[7] = {&r.q_WB[0], &r.q_WB[1], &r.q_WB[2], &r.q_WB[3], &r.v_W[0], &r.v_W[1], &r.v_W[2]};
      for (double *d : dst) {
        *d = parse_number(rd, f[k++], "IMU state");
        if (!std::isfinite(*d))
          rd.fail("NaN in the IMU state");
      }
      const double qn = std::hypot(std::hypot(r.q_WB[0], r.q_WB[1]), std::hypot(r.q_WB[2], r.q_WB[3]));
      if (std::abs(qn - 1.0) > 1e-6)
        rd.fail("q_WB is not a unit quaternion (norm " + std::to_string(qn) + ")");
    }
    if (!rows.empty() && r.t_cam_ns < rows.back().t_cam_ns)
      rd.fail("camera time goes back (rows must be in update order)");
    rows.push_back(r);
    have_row = rd.next(f);
  }
  return rows;
}

} // namespace ovton::core
