#pragma once
// Per-dimension min-max scaling to [0,1], fitted on the training window (paper Sec. IV-B/C).
#include "ov_msckf_ton/ton/ton_error.h"

#include <Eigen/Core>
#include <limits>

namespace ovton::msckf {
namespace ton {

template <int Dim> class MinMaxNormalizer {
public:
  using Vec = Eigen::Matrix<double, Dim, 1>;

  /// `min_range` (per dimension, in data units) keeps a flat window from being blown up: a dimension whose spread is
  /// below it is widened symmetrically to `min_range`, so its values map near 0.5 and a network error of e in
  /// normalised units stays an error of e * min_range in data units, never e / 0.
  explicit MinMaxNormalizer(const Vec &min_range = Vec::Constant(1e-12)) : min_range_(min_range) {
    OVTON_TON_CHECK((min_range.array() > 0.0).all(), "MinMaxNormalizer: min_range must be positive");
  }

  void reset() { count_ = 0; }
  /// Extend the running bounds with one sample; call finish() after the last one.
  void add(const Vec &x) {
    OVTON_TON_CHECK(x.allFinite(), "MinMaxNormalizer::add: non-finite sample");
    if (count_ == 0) {
      lo_ = x;
      hi_ = x;
    } else {
      lo_ = lo_.cwiseMin(x);
      hi_ = hi_.cwiseMax(x);
    }
    ++count_;
  }
  void finish() {
    OVTON_TON_CHECK(count_ > 0, "MinMaxNormalizer::finish: no samples");
    for (int d = 0; d < Dim; ++d) {
      double range = hi_[d] - lo_[d];
      double lo = lo_[d];
      if (range < min_range_[d]) {
        lo -= 0.5 * (min_range_[d] - range);
        range = min_range_[d];
      }
      offset_[d] = lo;
      scale_[d] = range;
    }
    fitted_ = true;
  }

  bool fitted() const { return fitted_; }
  Vec normalize(const Vec &x) const {
    OVTON_TON_CHECK(fitted_, "MinMaxNormalizer::normalize before fit");
    return (x - offset_).cwiseQuotient(scale_);
  }
  Vec denormalize(const Vec &xn) const {
    OVTON_TON_CHECK(fitted_, "MinMaxNormalizer::denormalize before fit");
    return offset_ + xn.cwiseProduct(scale_);
  }
  const Vec &offset() const { return offset_; }
  const Vec &scale() const { return scale_; }

private:
  Vec min_range_;
  Vec lo_ = Vec::Zero(), hi_ = Vec::Zero();
  Vec offset_ = Vec::Zero(), scale_ = Vec::Ones();
  long count_ = 0;
  bool fitted_ = false;
};

} // namespace ton
} // namespace ovton::msckf
