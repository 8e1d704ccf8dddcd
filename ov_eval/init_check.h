#pragma once
// How good an initialisation was, against ground truth: the first pose the filter wrote compared with the truth at
// its time, in the quantities an initialiser must get right (yaw and position are unobservable and left out).
#include "ov_core/types/sensor_data.h"

#include <vector>

namespace ovton::eval {

struct InitCheck {
  bool ok = false;           ///< false when the truth has no full state at that time
  double data_s = 0.0;       ///< images consumed before the first pose: first pose time − first image stamp [s]
  double tilt_err_deg = 0.0; ///< roll/pitch: angle between the estimated and true gravity direction in the body
  double vel_err_m_s = 0.0;  ///< |v| error in the body frame (free of the unobservable yaw)
  double speed_m_s = 0.0;    ///< true speed at that time
};

InitCheck check_initialisation(const ovton::core::StateSample &first, const std::vector<ovton::core::StateSample> &gt,
                               int64_t first_image_ns);

} // namespace ovton::eval
