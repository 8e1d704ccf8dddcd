#include "ov_eval/truth_camera.h"
#include "ov_core/types/state_interpolation.h"
#include "ov_core/types/time.h"
#include "ov_eval/metrics.h"

namespace ovton::eval {

TruthCamera::TruthCamera(const ovton::core::Dataset &d)
    : d_(d), R_BC_(d.cam.T_BC.topLeftCorner<3, 3>()), p_BC_(d.cam.T_BC.topRightCorner<3, 1>()) {}

int64_t TruthCamera::t_imu(int64_t t_cam_ns) const {
  return t_cam_ns + ovton::core::s_to_ns(d_.has_td_truth() ? td_truth_at(d_.td_truth, t_cam_ns) : d_.td_prior_s);
}

bool TruthCamera::at_imu(int64_t t_imu_ns, CameraPose &c) const {
  ovton::core::StateSample s;
  if (!ovton::core::interpolate_state(d_.groundtruth, t_imu_ns, s))
    return false;
  const Eigen::Matrix3d R_WB = s.q_WB.toRotationMatrix();
  c.R_WC = R_WB * R_BC_;
  c.p_WC = s.p + R_WB * p_BC_;
  return true;
}

} // namespace ovton::eval
