#include "drivers/libcamera/libcamera_camera_config.h"

#include <cmath>

#include "drivers/libcamera/libcamera_format.h"
#include "drivers/pixel/raw_image.h"

namespace cblox {
namespace {

constexpr unsigned int kMaxBuffers = 32;
constexpr double kMaxRateHz = 1000.0;

std::string number(double value) {
  std::string text = std::to_string(value);
  // Trim std::to_string's trailing zeros ("30.500000" -> "30.5").
  if (text.find('.') != std::string::npos) {
    text.erase(text.find_last_not_of('0') + 1);
    if (text.back() == '.') text.pop_back();
  }
  return text;
}

}  // namespace

std::string LibcameraCameraConfig::validate() const {
  if (camera_id.empty() || camera_id == "libcamera:") {
    return "camera_id is empty: give a libcamera camera id or an index such as 0";
  }
  std::string format_error;
  const std::optional<libcamera::PixelFormat> format =
      parseLibcameraPixelFormat(pixel_format, &format_error);
  if (!format) return "pixel_format: " + format_error;
  for (const auto& [name, value] :
       {std::pair<const char*, int>{"width", width}, {"height", height}}) {
    if (value < 1 || value > kMaxImageSide) {
      return std::string(name) + " must be in [1, " + std::to_string(kMaxImageSide) + "], got " +
             std::to_string(value);
    }
  }
  const PixelFormat layout = *pixelFormatFromLibcamera(*format);
  const bool even_width = layout == PixelFormat::kYuyv || layout == PixelFormat::kUyvy ||
                          layout == PixelFormat::kNv12 || layout == PixelFormat::kYuv420;
  const bool even_height = layout == PixelFormat::kNv12 || layout == PixelFormat::kYuv420;
  if (even_width && width % 2 != 0) {
    return "width must be even for " + pixel_format + ", got " + std::to_string(width);
  }
  if (even_height && height % 2 != 0) {
    return "height must be even for " + pixel_format + ", got " + std::to_string(height);
  }
  if (!std::isfinite(rate_hz) || rate_hz < 0.0 || rate_hz > kMaxRateHz) {
    return "rate_hz must be in [0, " + number(kMaxRateHz) + "] (0 = the camera's rate), got " +
           number(rate_hz);
  }
  if (buffer_count < 1 || buffer_count > kMaxBuffers) {
    return "buffer_count must be in [1, " + std::to_string(kMaxBuffers) + "], got " +
           std::to_string(buffer_count);
  }
  if (exposure_us && *exposure_us <= 0) {
    return "exposure_us must be > 0 (leave it unset for automatic exposure), got " +
           std::to_string(*exposure_us);
  }
  if (analogue_gain && !(std::isfinite(*analogue_gain) && *analogue_gain > 0.0)) {
    return "analogue_gain must be finite and > 0 (leave it unset for automatic gain), got " +
           number(*analogue_gain);
  }
  return {};
}

}  // namespace cblox
