#include "ov_core/io/trajectory_io.h"
#include "ov_core/io/csv.h"
#include "ov_core/types/errors.h"

#include <cmath>
#include <cstdio>
#include <iomanip>
#include <optional>

namespace ovton::core {

const char *const kTrajectoryCsvHeader =
    "timestamp_ns,px,py,pz,qw,qx,qy,qz,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz,td_s,td_sigma_s";

namespace {

/// "1403715274.30214" -> ns without going through a double (a double keeps only ~0.1 us at 1.4e9 s).
int64_t seconds_field_to_ns(const TextTableReader &r, const std::string &f) {
  const bool negative = !f.empty() && f[0] == '-';
  const std::string body = !f.empty() && (f[0] == '-' || f[0] == '+') ? f.substr(1) : f;
  const auto dot = body.find('.');
  const std::string ip = body.substr(0, dot);
  std::string fp = dot == std::string::npos ? "" : body.substr(dot + 1);
  const bool plain = (!ip.empty() || !fp.empty()) && ip.find_first_not_of("0123456789") == std::string::npos &&
                     fp.find_first_not_of("0123456789") == std::string::npos;
  std::optional<int64_t> ns;
  if (plain) {
    const int64_t sec = ip.empty() ? 0 : r.to_int64(ip, "timestamp [s]");
    fp = fp.substr(0, 9);
    fp.resize(9, '0');
    ns = try_seconds_parts_to_ns(sec, r.to_int64(fp, "timestamp fraction"), negative);
  } else {
    // Exponent notation or other forms: through a double (fine for small, relative stamps).
    ns = try_s_to_ns(r.to_double(f, "timestamp [s]"));
  }
  if (!ns)
    r.fail("timestamp '" + f + "' s is beyond the int64 nanosecond clock (+-292 years)");
  return *ns;
}

Eigen::Quaterniond make_quat(const TextTableReader &r, double w, double x, double y, double z) {
  Eigen::Quaterniond q(w, x, y, z);
  const double n = q.norm();
  if (std::abs(n - 1.0) > 1e-2)
    r.fail("quaternion is not unit length (norm " + std::to_string(n) + ")");
  q.normalize();
  return q;
}

void check_order(const TextTableReader &r, const std::vector<StateSample> &out, int64_t t) {
  if (!out.empty() && t <= out.back().t_ns)
    r.fail(t == out.back().t_ns ? "duplicate timestamp" : "timestamp is not after the previous row");
}

} // namespace

TrajectoryWriter::TrajectoryWriter(const std::string &file, TrajectoryFormat fmt, int camera_tds)
    : file_(file), fmt_(fmt), camera_tds_(fmt == TrajectoryFormat::Csv ? camera_tds : 0) {
  out_.open(file, std::ios::out | std::ios::trunc);
  if (!out_)
    throw DataError(file, "cannot open for writing");
  out_ << std::setprecision(9);
  if (fmt_ == TrajectoryFormat::Csv) {
    out_ << kTrajectoryCsvHeader;
    for (int k = 1; k <= camera_tds_; ++k)
      out_ << ",td_cam" << k << "_s,td_cam" << k << "_sigma_s";
    out_ << "\n";
  } else
    out_ << "# timestamp(s) tx ty tz qx qy qz qw\n";
  out_.flush();
}

void TrajectoryWriter::write(const StateSample &s) {
  const auto &q = s.q_WB;
  // t_d to 12 significant digits; its sigma to 7, the precision of the single-precision covariance the estimator
  // reports it from, rather than that float's decimal expansion (0.00999999987 for 0.01).
  if (fmt_ == TrajectoryFormat::Csv) {
    out_ << s.t_ns << ',' << s.p.x() << ',' << s.p.y() << ',' << s.p.z() << ',' << q.w() << ',' << q.x() << ',' << q.y()
         << ',' << q.z() << ',' << s.v.x() << ',' << s.v.y() << ',' << s.v.z() << ',' << s.bg.x() << ',' << s.bg.y()
         << ',' << s.bg.z() << ',' << s.ba.x() << ',' << s.ba.y() << ',' << s.ba.z() << ',' << std::setprecision(12)
         << s.td_s << ',' << std::setprecision(7) << s.td_sigma_s;
    for (size_t k = 0; k < static_cast<size_t>(camera_tds_); ++k) {
      const bool has = k < s.cam_td_s.size();
      out_ << ',' << std::setprecision(12) << (has ? s.cam_td_s[k] : std::nan("")) << ',' << std::setprecision(7)
           << (has ? s.cam_td_sigma_s[k] : std::nan(""));
    }
    out_ << std::setprecision(9) << "\n";
  } else {
    // Sign and magnitude apart: -1.5 s is "-1.500000000", not "-1.-500000000".
    const unsigned long long mag =
        s.t_ns < 0 ? 0ULL - static_cast<unsigned long long>(s.t_ns) : static_cast<unsigned long long>(s.t_ns);
    char stamp[40];
    std::snprintf(stamp, sizeof(stamp), "%s%llu.%09llu", s.t_ns < 0 ? "-" : "", mag / 1000000000ULL,
                  mag % 1000000000ULL);
    out_ << stamp << ' ' << s.p.x() << ' ' << s.p.y() << ' ' << s.p.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z()
         << ' ' << q.w() << "\n";
  }
  // Flushed per row: an interrupted run keeps every pose it produced.
  out_.flush();
  if (!out_)
    throw DataError(file_, "write failed (disk full?)");
}

std::vector<StateSample> read_trajectory(const std::string &file) {
  require_file(file);
  // Sniff the separator from the first data line.
  char sep = ',';
  {
    std::ifstream in(file);
    std::string line;
    while (std::getline(in, line)) {
      if (line.rfind(kUtf8Bom, 0) == 0)
        line.erase(0, 3);
      if (line.empty() || line[0] == '#' || line.find_first_not_of(" \t\r") == std::string::npos)
        continue;
      sep = line.find(',') != std::string::npos ? ',' : ' ';
      break;
    }
  }
  TextTableReader r(file, sep);
  std::vector<StateSample> out;
  std::vector<std::string> f;
  size_t ncols = 0;
  while (r.next(f)) {
    if (ncols == 0) {
      ncols = f.size();
      const bool ok =
          sep == ' ' ? ncols == 8 : (ncols == 17 || (ncols >= 19 && ncols % 2 == 1) || ncols == 8 || ncols == 4);
      if (!ok)
        r.fail("unrecognised trajectory layout with " + std::to_string(ncols) +
               " columns (expected CSV with 4, 8, 17 or 19 (+2 per further camera's offset) columns, or 8 "
               "space-separated TUM columns)");
    } else if (f.size() != ncols) {
      r.fail("expected " + std::to_string(ncols) + " columns like the first row, found " + std::to_string(f.size()));
    }
    StateSample s;
    std::vector<double> v(ncols);
    for (size_t i = 1; i < ncols; ++i)
      v[i] = r.to_double(f[i], "value");
    if (sep == ' ') {
      s.t_ns = seconds_field_to_ns(r, f[0]);
      s.p = Eigen::Vector3d(v[1], v[2], v[3]);
      s.q_WB = make_quat(r, v[7], v[4], v[5], v[6]);
    } else {
      s.t_ns = r.to_int64(f[0], "timestamp [ns]");
      s.p = Eigen::Vector3d(v[1], v[2], v[3]);
      if (ncols == 4) {
        s.has_orientation = false;
      } else {
        s.q_WB = make_quat(r, v[4], v[5], v[6], v[7]);
      }
      if (ncols >= 17) {
        s.v = Eigen::Vector3d(v[8], v[9], v[10]);
        s.bg = Eigen::Vector3d(v[11], v[12], v[13]);
        s.ba = Eigen::Vector3d(v[14], v[15], v[16]);
        s.has_velocity = true;
      }
      if (ncols >= 19) {
        s.td_s = v[17];
        s.td_sigma_s = v[18];
        s.has_td = true;
      }
      for (size_t i = 19; i + 1 < ncols; i += 2) {
        s.cam_td_s.push_back(v[i]);
        s.cam_td_sigma_s.push_back(v[i + 1]);
      }
    }
    check_order(r, out, s.t_ns);
    out.push_back(s);
  }
  if (out.empty())
    throw DataError(file, "no trajectory rows");
  return out;
}

void write_euroc_groundtruth(const std::string &file, const std::vector<StateSample> &gt) {
  std::ofstream out(file, std::ios::out | std::ios::trunc);
  if (!out)
    throw DataError(file, "cannot open for writing");
  out << "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
         "v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], "
         "b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]\n";
  out << std::setprecision(10);
  for (const auto &s : gt) {
    const auto &q = s.q_WB;
    out << s.t_ns << ',' << s.p.x() << ',' << s.p.y() << ',' << s.p.z() << ',' << q.w() << ',' << q.x() << ',' << q.y()
        << ',' << q.z() << ',' << s.v.x() << ',' << s.v.y() << ',' << s.v.z() << ',' << s.bg.x() << ',' << s.bg.y()
        << ',' << s.bg.z() << ',' << s.ba.x() << ',' << s.ba.y() << ',' << s.ba.z() << "\n";
  }
  if (!out)
    throw DataError(file, "write failed");
}

std::vector<TdSample> read_td_truth(const std::string &file) {
  TextTableReader r(file, ',');
  std::vector<TdSample> out;
  std::vector<std::string> f;
  while (r.next(f)) {
    if (f.size() != 2)
      r.fail("expected 2 columns (timestamp_ns, td_s), found " + std::to_string(f.size()));
    TdSample s;
    s.t_cam_ns = r.to_int64(f[0], "timestamp [ns]");
    s.td_s = r.to_double(f[1], "td_s");
    if (std::abs(s.td_s) > 10.0)
      r.fail("time offset " + f[1] + " s is not a camera-IMU offset (more than 10 s)");
    if (!out.empty() && s.t_cam_ns <= out.back().t_cam_ns)
      r.fail(s.t_cam_ns == out.back().t_cam_ns ? "duplicate timestamp" : "timestamp is not after the previous row");
    out.push_back(s);
  }
  if (out.empty())
    throw DataError(file, "no rows");
  return out;
}

void write_td_truth(const std::string &file, const std::vector<TdSample> &td) {
  std::ofstream out(file, std::ios::out | std::ios::trunc);
  if (!out)
    throw DataError(file, "cannot open for writing");
  out << "#timestamp_ns,td_s\n" << std::setprecision(12);
  for (const auto &s : td)
    out << s.t_cam_ns << ',' << s.td_s << "\n";
  if (!out)
    throw DataError(file, "write failed");
}

} // namespace ovton::core
