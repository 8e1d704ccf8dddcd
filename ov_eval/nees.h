#pragma once
// Normalised estimation error squared (NEES) of an estimator's own covariance against ground truth: the filter's
// consistency check (3 is ideal for a 3-dof block, 1 for t_d). Kept on the evaluation side: the estimator hands out
// samples with their covariance (StateSample::P_pose, td_sigma_s) and knows nothing about the truth.
#include "ov_core/types/sensor_data.h"

#include <vector>

namespace ovton::eval {

struct NeesStats {
  double ori_sum = 0, pos_sum = 0, td_sum = 0;
  long count = 0, td_count = 0;
  struct Sample {
    int64_t t_ns;
    double ori, pos, td; ///< td is NaN where it has no sigma or no truth
  };
  std::vector<Sample> per_frame; ///< for `ovton run --nees-log`
  double ori() const { return count ? ori_sum / count : 0.0; }
  double pos() const { return count ? pos_sum / count : 0.0; }
  double td() const { return td_count ? td_sum / td_count : 0.0; }
};

/// Accumulates NEES over an estimator's samples. Only meaningful when the estimate lives in the ground truth's frame
/// (ground-truth initialisation). Errors in the estimator's convention (ov_msckf_ton/state/state.h):
/// R_true = Exp(δθ)·R̂, p_true = p̂ + δp, t_d,true = t̂_d + δt_d.
class NeesAccumulator {
public:
  NeesAccumulator(const std::vector<ovton::core::StateSample> &groundtruth,
                  const std::vector<ovton::core::TdSample> &td_truth)
      : gt_(groundtruth), td_truth_(td_truth) {}
  /// Samples without a pose covariance, or outside the ground truth's span, are skipped.
  void add(const ovton::core::StateSample &est);
  const NeesStats &stats() const { return stats_; }

private:
  const std::vector<ovton::core::StateSample> &gt_;
  const std::vector<ovton::core::TdSample> &td_truth_;
  NeesStats stats_;
};

} // namespace ovton::eval
