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

namespace ov_core {

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
  // The header is the last non-'#' line the reader skipped before the first data row.
  std::string header;
  for (auto it = rd.comments().rbegin(); it != rd.comments().rend(); ++it)
    if (!it->empty() && (*it)[0] != '#') {
      header = *it;
      break;
    }
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

} // namespace ov_core
