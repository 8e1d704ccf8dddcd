#include "ov_msckf_ton/update/residual_log.h"
#include "ov_core/types/errors.h"

namespace ov_msckf_ton {

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
