#include "ov_eval/init_check.h"
#include "ov_core/types/state_interpolation.h"

#include <algorithm>
#include <cmath>

namespace ovton::eval {

InitCheck check_initialisation(const ovton::core::StateSample &first, const std::vector<ovton::core::StateSample> &gt,
                               int64_t first_image_ns) {
  InitCheck c;
  ovton::core::StateSample g;
  if (gt.empty() || !gt.front().has_orientation || !gt.front().has_velocity ||
      !ovton::core::interpolate_state(gt, first.t_ns, g))
    return c;
  const Eigen::Matrix3d Re = first.q_WB.toRotationMatrix(), Rg = g.q_WB.toRotationMatrix();
  const Eigen::Vector3d ze = Re.transpose() * Eigen::Vector3d::UnitZ(), zg = Rg.transpose() * Eigen::Vector3d::UnitZ();
  c.tilt_err_deg = std::acos(std::clamp(ze.dot(zg), -1.0, 1.0)) * 180.0 / M_PI;
  c.vel_err_m_s = (Re.transpose() * first.v - Rg.transpose() * g.v).norm();
  c.speed_m_s = g.v.norm();
  c.data_s = 1e-9 * static_cast<double>(first.t_ns - first_image_ns);
  c.ok = true;
  return c;
}

} // namespace ovton::eval
