#include "ov_core/cam/camera_calib.h"

namespace ovton::core {

std::string to_string(DistortionModel m) {
  return m == DistortionModel::RadTan ? "radtan" : "equidistant";
}

} // namespace ovton::core
