#include "ov_core/io/velocity_log.h"
#include "ov_core/io/csv.h"
#include "ov_core/io/text_format.h"
#include "ov_core/types/errors.h"

#include <cmath>

namespace ovton::core {

namespace {

// The column list, once: name and accessor for writing and reading.
struct Column {
  const char *name;
  double VelocityLogRow::*d = nullptr;
  int VelocityLogRow::*i = nullptr;
};
const Column kColumns[] = {
    {"u_px", &VelocityLogRow::u_px},
    {"v_px", &VelocityLogRow::v_px},
    {"x_norm", &VelocityLogRow::x_norm},
    {"y_norm", &VelocityLogRow::y_norm},
    {"eq2_x", &VelocityLogRow::eq2_x},
    {"eq2_y", &VelocityLogRow::eq2_y},
    {"next_x", &VelocityLogRow::next_x},
    {"next_y", &VelocityLogRow::next_y},
    {"its_x", &VelocityLogRow::its_x},
    {"its_y", &VelocityLogRow::its_y},
    {"f2f_x", &VelocityLogRow::f2f_x},
    {"f2f_y", &VelocityLogRow::f2f_y},
    {"used_source", nullptr, &VelocityLogRow::used_source},
    {"fvon_source", nullptr, &VelocityLogRow::fvon_source},
    {"gated", nullptr, &VelocityLogRow::gated},
    {"focal_px", &VelocityLogRow::focal_px},
};
constexpr int kLeading = 4; // t_cam_ns, feature_id, obs_index, track_length

} // namespace

VelocityLogWriter::VelocityLogWriter(const std::string &path) : path_(path), out_(path) {
  if (!out_)
    throw DataError(path, "cannot open the velocity log for writing");
  out_ << header() << '\n' << std::flush;
}

std::string VelocityLogWriter::header() {
  std::string h = "t_cam_ns,feature_id,obs_index,track_length";
  for (const Column &c : kColumns)
    h += std::string(",") + c.name;
  return h;
}

void VelocityLogWriter::write(const std::vector<VelocityLogRow> &rows) {
  for (const auto &r : rows) {
    out_ << r.t_cam_ns << ',' << r.feature_id << ',' << r.obs_index << ',' << r.track_length;
    for (const Column &c : kColumns) {
      out_ << ',';
      if (c.d)
        out_ << csv_number(r.*(c.d));
      else
        out_ << r.*(c.i);
    }
    out_ << '\n';
  }
  out_.flush();
  if (!out_)
    throw DataError(path_, "write failed (disk full?)");
}

std::vector<VelocityLogRow> read_velocity_log(const std::string &path) {
  require_file(path);
  TextTableReader rd(path, ',');
  std::vector<VelocityLogRow> rows;
  std::vector<std::string> f;
  const size_t n = kLeading + sizeof(kColumns) / sizeof(kColumns[0]);
  while (rd.next(f)) {
    if (f.size() != n)
      rd.fail("expected " + std::to_string(n) + " columns (" + VelocityLogWriter::header() + "), found " +
              std::to_string(f.size()));
    VelocityLogRow r;
    r.t_cam_ns = rd.to_int64(f[0], "t_cam_ns");
    r.feature_id = static_cast<uint64_t>(rd.to_int64(f[1], "feature_id"));
    r.obs_index = static_cast<int>(rd.to_int64(f[2], "obs_index"));
    r.track_length = static_cast<int>(rd.to_int64(f[3], "track_length"));
    size_t k = kLeading;
    for (const Column &c : kColumns) {
      const std::string &v = f[k++];
      if (c.d)
        r.*(c.d) = v.empty() || v == "nan" ? VelocityLogRow::kNaN : rd.to_double(v, c.name);
      else
        r.*(c.i) = static_cast<int>(rd.to_int64(v, c.name));
    }
    rows.push_back(r);
  }
  return rows;
}

} // namespace ovton::core
