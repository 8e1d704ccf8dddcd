#include "ov_eval/nees.h"
#include "ov_core/math/so3.h"
#include "ov_core/types/state_interpolation.h"
#include "ov_eval/metrics.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>

namespace ovton::eval {

void NeesAccumulator::add(const ovton::core::StateSample &est) {
  ovton::core::StateSample g;
  if (!est.has_pose_cov || !ovton::core::interpolate_state(gt_, est.t_ns, g))
    return;
  const Eigen::Vector3d e_th =
      ovton::core::so3_log(g.q_WB.toRotationMatrix() * est.q_WB.toRotationMatrix().transpose());
  const Eigen::Vector3d e_p = g.p - est.p;
  const Eigen::Matrix3d P_th = est.P_pose.topLeftCorner<3, 3>();
  const Eigen::Matrix3d P_p = est.P_pose.bottomRightCorner<3, 3>();
  const double n_ori = e_th.dot(P_th.ldlt().solve(e_th)), n_pos = e_p.dot(P_p.ldlt().solve(e_p));
  double n_td = std::numeric_limits<double>::quiet_NaN();
  if (est.has_td && est.td_sigma_s > 0 && !td_truth_.empty()) {
    const double e_td = td_truth_at(td_truth_, est.t_ns - ovton::core::s_to_ns(est.td_s)) - est.td_s;
    n_td = e_td * e_td / (est.td_sigma_s * est.td_sigma_s);
    stats_.td_sum += n_td;
    ++stats_.td_count;
  }
  stats_.ori_sum += n_ori;
  stats_.pos_sum += n_pos;
  ++stats_.count;
  stats_.per_frame.push_back({est.t_ns, n_ori, n_pos, n_td});
}

} // namespace ovton::eval
