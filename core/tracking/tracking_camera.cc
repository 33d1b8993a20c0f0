#include "core/tracking/tracking_camera.h"

#include <cmath>
#include <sstream>

namespace cblox {

std::string TrackingCamera::validate() const {
  if (std::string e = cblox::validate(intrinsics); !e.empty()) return "intrinsics: " + e;
  std::ostringstream error;
  if (!std::isfinite(baseline_m) || baseline_m <= 0.0) {
    error << "baseline_m must be finite and > 0, got " << baseline_m;
  } else if (!std::isfinite(close_depth_m) || close_depth_m <= 0.0) {
    error << "close_depth_m must be finite and > 0, got " << close_depth_m;
  }
  return error.str();
}

}  // namespace cblox
