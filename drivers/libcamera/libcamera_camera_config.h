#pragma once

#include <optional>
#include <string>

namespace cblox {

/// What to ask of a libcamera camera (LibcameraCamera::open). Plain value type; check it with
/// validate().
struct LibcameraCameraConfig {
  /// The camera: its libcamera id (as `cam --list` prints it), optionally prefixed with
  /// "libcamera:", or a decimal index into the cameras present ("0").
  std::string camera_id = "0";
  /// Stream format, as parseLibcameraPixelFormat() reads it ("YUYV", "MJPEG", "NV12",
  /// "YUV420", "GREY", "RGB24", libcamera's "RGB888", ...).
  std::string pixel_format = "YUYV";
  int width = 640;   ///< pixels; the whole side-by-side frame for a stereo camera
  int height = 480;  ///< pixels
  /// Frame rate asked of the camera through FrameDurationLimits (both limits 1e6 / rate_hz
  /// microseconds); 0 = leave the camera's own rate.
  double rate_hz = 30.0;
  /// Buffers (and requests) in flight; the camera may raise it.
  unsigned int buffer_count = 4;
  /// Manual exposure time in microseconds (sets AeEnable false); unset = automatic.
  std::optional<int> exposure_us;
  /// Manual analogue gain, 1.0 = unity (sets AeEnable false); unset = automatic.
  std::optional<double> analogue_gain;

  /// Returns "" when usable, else a message naming the first bad field and its value:
  /// camera_id empty; pixel_format not parseable (parseLibcameraPixelFormat's message);
  /// width or height outside [1, 16384], or odd where the format needs even sizes (YUYV,
  /// UYVY: width; NV12, YUV420: both); rate_hz not finite or < 0, or > 1000; buffer_count
  /// outside [1, 32]; exposure_us <= 0; analogue_gain not finite or <= 0. Thread-safe (pure).
  std::string validate() const;
};

}  // namespace cblox
