#include "core/optimization/stereo_camera_model.h"

#include <cmath>
#include <sstream>

namespace cblox {
namespace {

std::string positiveFieldError(const char* field, double value) {
  std::ostringstream os;
  os << field << " must be > 0 and finite, got " << value;
  return os.str();
}

}  // namespace

std::string validate(const StereoCameraModel& c) {
  // Written as !(x > 0) so that NaN is rejected too.
  if (!(c.fx > 0) || !std::isfinite(c.fx)) return positiveFieldError("fx", c.fx);
  if (!(c.fy > 0) || !std::isfinite(c.fy)) return positiveFieldError("fy", c.fy);
  if (!(c.bf > 0) || !std::isfinite(c.bf)) return positiveFieldError("bf", c.bf);
  if (!std::isfinite(c.cx)) return "cx must be finite";
  if (!std::isfinite(c.cy)) return "cy must be finite";
  return {};
}

StereoCameraModel stereoCameraModelFrom(const RectifiedStereoCalibration& calibration) {
  const PinholeIntrinsics& in = calibration.intrinsics;
  return StereoCameraModel{in.fx, in.fy, in.cx, in.cy, in.fx * calibration.baseline_m};
}

}  // namespace cblox
