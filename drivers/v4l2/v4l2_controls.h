#pragma once

// Camera controls cblox sets by name, and their V4L2 control ids.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace cblox {

/// The V4L2 control id (V4L2_CID_*) of a control name cblox knows:
///   "exposure_absolute" V4L2_CID_EXPOSURE_ABSOLUTE (units of 100 us)
///   "exposure_auto"     V4L2_CID_EXPOSURE_AUTO (menu: 0 auto, 1 manual, 2 shutter
///                       priority, 3 aperture priority)
///   "gain"              V4L2_CID_GAIN
/// std::nullopt for any other name. Thread-safe (pure).
std::optional<uint32_t> controlIdFromName(std::string_view name);

/// "exposure_absolute, exposure_auto, gain". Thread-safe (pure).
std::string knownControlNames();

/// Range of a control as VIDIOC_QUERYCTRL reports it. Plain value type.
struct V4l2ControlRange {
  int64_t minimum = 0;
  int64_t maximum = 0;
  int64_t step = 1;
  int64_t default_value = 0;
};

/// Empty if `value` is within [minimum, maximum] and on the step grid (minimum + k * step,
/// step <= 1 meaning any value), else "<name> <value> is out of range [min, max]" or
/// "<name> <value> is not minimum + a multiple of <step>". Thread-safe (pure).
std::string checkControlValue(std::string_view name, int64_t value, const V4l2ControlRange& range);

}  // namespace cblox
