#pragma once

// What a V4L2 capture device offers: pixel formats, frame sizes and frame rates, and their
// description for error messages and `cblox-capture --list`.

#include <cstdint>
#include <string>
#include <vector>

namespace cblox {

/// One frame size of a format (VIDIOC_ENUM_FRAMESIZES) with its frame rates
/// (VIDIOC_ENUM_FRAMEINTERVALS). Plain value type.
struct V4l2FrameSize {
  int width = 0;  ///< the size; for a stepwise range its maximum
  int height = 0;
  /// Stepwise or continuous range of sizes: min_* .. width x height in steps of step_*.
  bool stepwise = false;
  int min_width = 0, min_height = 0, step_width = 1, step_height = 1;
  /// Discrete frame rates (Hz), as the driver lists them.
  std::vector<double> rates_hz;
  /// A continuous or stepwise range of rates, when the driver gives one (else both 0).
  double min_rate_hz = 0.0;
  double max_rate_hz = 0.0;
};

/// One pixel format of a device (VIDIOC_ENUM_FMT). Plain value type.
struct V4l2FormatInfo {
  uint32_t fourcc = 0;
  std::string description;  ///< the driver's, e.g. "YUYV 4:2:2"
  bool compressed = false;  ///< V4L2_FMT_FLAG_COMPRESSED
  bool emulated = false;    ///< V4L2_FMT_FLAG_EMULATED: converted in software by libv4l
  std::vector<V4l2FrameSize> sizes;
};

/// One line per format:
///   "YUYV (YUYV 4:2:2): 640x480 @ 30/15 Hz, 1280x720 @ 10 Hz"
///   "MJPG (Motion-JPEG, compressed): 1920x1080 @ 30 Hz"
///   "RGB3 (RGB3, emulated): 16x16..1920x1080 step 2x2 @ 1-60 Hz"
///   "H264 (H.264, compressed, not supported by cblox): ..."
/// Rates print with up to 3 significant decimals (7.5, 29.97); a size without known rates
/// prints without " @ ...". "(no formats)" for an empty list. Thread-safe (pure).
std::string describeFormats(const std::vector<V4l2FormatInfo>& formats);

/// "30", "7.5", "29.97": a rate in Hz with trailing zeros removed. Thread-safe (pure).
std::string formatRateHz(double rate_hz);

}  // namespace cblox
