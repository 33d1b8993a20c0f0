#include "drivers/v4l2/v4l2_controls.h"

#include <linux/videodev2.h>

namespace cblox {

std::optional<uint32_t> controlIdFromName(std::string_view name) {
  if (name == "exposure_absolute") return V4L2_CID_EXPOSURE_ABSOLUTE;
  if (name == "exposure_auto") return V4L2_CID_EXPOSURE_AUTO;
  if (name == "gain") return V4L2_CID_GAIN;
  return std::nullopt;
}

std::string knownControlNames() { return "exposure_absolute, exposure_auto, gain"; }

std::string checkControlValue(std::string_view name, int64_t value, const V4l2ControlRange& range) {
  const std::string prefix = std::string(name) + " " + std::to_string(value);
  if (value < range.minimum || value > range.maximum) {
    return prefix + " is out of range [" + std::to_string(range.minimum) + ", " +
           std::to_string(range.maximum) + "]";
  }
  if (range.step > 1 && (value - range.minimum) % range.step != 0) {
    return prefix + " is not " + std::to_string(range.minimum) + " + a multiple of " +
           std::to_string(range.step);
  }
  return {};
}

}  // namespace cblox
