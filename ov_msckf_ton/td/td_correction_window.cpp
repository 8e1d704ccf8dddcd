#include "ov_msckf_ton/td/td_correction_window.h"

#include <algorithm>
#include <cmath>

namespace ovton::msckf {

double TdCorrectionWindow::Sum::z() const {
  return allowed_var > 0 ? std::abs(moved) / std::sqrt(allowed_var) : 0.0;
}

void TdCorrectionWindow::add(int64_t t_ns, double td_prior, double var_prior, double td_post, double var_post) {
  if (first_ns_ < 0)
    first_ns_ = t_ns;
  corrections_.push_back({t_ns, td_post - td_prior, std::max(0.0, var_prior - var_post)});
  while (!corrections_.empty() && t_ns - corrections_.front().t_ns > keep_ns_)
    corrections_.pop_front();
}

TdCorrectionWindow::Sum TdCorrectionWindow::sum(int64_t end_ns, double window_s) const {
  Sum r;
  const int64_t begin_ns = end_ns - static_cast<int64_t>(window_s * 1e9);
  r.covered = first_ns_ >= 0 && first_ns_ <= begin_ns;
  for (const Correction &c : corrections_)
    if (c.t_ns > begin_ns && c.t_ns <= end_ns) {
      r.moved += c.delta;
      r.allowed_var += c.var_drop;
    }
  return r;
}

void TdCorrectionWindow::clear() {
  corrections_.clear();
  first_ns_ = -1;
}

} // namespace ovton::msckf
