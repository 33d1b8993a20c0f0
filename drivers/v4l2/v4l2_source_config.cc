#include "drivers/v4l2/v4l2_source_config.h"

#include <cmath>

#include "drivers/pixel/pixel_format.h"
#include "drivers/pixel/raw_image.h"

namespace cblox {
namespace {

bool positive(double value) { return std::isfinite(value) && value > 0.0; }

}  // namespace

std::string_view v4l2ModeName(V4l2Mode mode) {
  switch (mode) {
    case V4l2Mode::kMono:
      return "mono";
    case V4l2Mode::kDepth:
      return "depth";
    case V4l2Mode::kStereoPair:
      return "stereo_pair";
    case V4l2Mode::kSideBySide:
      return "side_by_side";
  }
  return "unknown";
}

std::optional<V4l2Mode> v4l2ModeFromName(std::string_view name) {
  for (V4l2Mode mode :
       {V4l2Mode::kMono, V4l2Mode::kDepth, V4l2Mode::kStereoPair, V4l2Mode::kSideBySide}) {
    if (name == v4l2ModeName(mode)) return mode;
  }
  return std::nullopt;
}

std::string V4l2SourceConfig::validate() const {
  const size_t wanted = mode == V4l2Mode::kStereoPair ? 2 : 1;
  if (devices.size() != wanted) {
    return "devices: mode " + std::string(v4l2ModeName(mode)) + " takes " + std::to_string(wanted) +
           " device(s), got " + std::to_string(devices.size());
  }
  for (const std::string& device : devices) {
    if (device.empty()) return "devices: empty path";
  }
  if (wanted == 2 && devices[0] == devices[1]) {
    return "devices: left and right are the same device " + devices[0];
  }
  const std::optional<PixelFormat> format = pixelFormatFromName(pixel_format);
  if (!format) return "pixel_format: unknown format '" + pixel_format + "'";
  if (mode != V4l2Mode::kSideBySide && *format == PixelFormat::kY8i) {
    return "pixel_format: Y8I is interleaved stereo (left and right in one frame); use mode "
           "side_by_side";
  }
  const bool depth_format = *format == PixelFormat::kZ16 || *format == PixelFormat::kY16;
  if (mode == V4l2Mode::kDepth && !depth_format) {
    return "pixel_format: depth mode needs Z16 (or Y16), got " + pixel_format;
  }
  if (mode != V4l2Mode::kDepth && *format == PixelFormat::kZ16) {
    return "pixel_format: Z16 is depth; use mode depth";
  }
  if (width <= 0 || height <= 0 || width > kMaxImageSide || height > kMaxImageSide) {
    return "width/height: must be within 1.." + std::to_string(kMaxImageSide) + ", got " +
           std::to_string(width) + "x" + std::to_string(height);
  }
  // Y8I interleaves its two views pixel by pixel: no halves, any width.
  if (mode == V4l2Mode::kSideBySide && *format != PixelFormat::kY8i && width % 2 != 0) {
    return "width: side_by_side needs an even width, got " + std::to_string(width);
  }
  if (!std::isfinite(rate_hz) || rate_hz < 0.0) {
    return "rate_hz: must be >= 0, got " + std::to_string(rate_hz);
  }
  if (buffer_count < 2 || buffer_count > 32) {
    return "buffer_count: must be 2..32, got " + std::to_string(buffer_count);
  }
  if (mode == V4l2Mode::kStereoPair && !positive(pair_tolerance_ms)) {
    return "pair_tolerance_ms: must be > 0, got " + std::to_string(pair_tolerance_ms);
  }
  if (exposure && *exposure < 0) return "exposure: must be >= 0";
  if (gain && *gain < 0) return "gain: must be >= 0";
  if (mode == V4l2Mode::kDepth) {
    if (!positive(depth_scale_m)) {
      return "depth_scale_m: must be > 0, got " + std::to_string(depth_scale_m);
    }
    if (!(std::isfinite(depth_min_m) && depth_min_m >= 0.0 && positive(depth_max_m) &&
          depth_max_m > depth_min_m)) {
      return "depth_min_m/depth_max_m: need 0 <= min < max";
    }
    if (depth_intrinsics) {
      if (std::string problem = cblox::validate(*depth_intrinsics); !problem.empty()) {
        return "depth_intrinsics: " + problem;
      }
      if (depth_intrinsics->width != width || depth_intrinsics->height != height) {
        return "depth_intrinsics: size " + std::to_string(depth_intrinsics->width) + "x" +
               std::to_string(depth_intrinsics->height) + " differs from the frame " +
               std::to_string(width) + "x" + std::to_string(height);
      }
    }
  }
  if (!positive(reopen_min_s) || !positive(reopen_max_s) || reopen_max_s < reopen_min_s) {
    return "reopen_min_s/reopen_max_s: need 0 < min <= max";
  }
  if (!positive(frame_timeout_s)) {
    return "frame_timeout_s: must be > 0, got " + std::to_string(frame_timeout_s);
  }
  if (stalls_before_reopen < 1) return "stalls_before_reopen: must be >= 1";
  return {};
}

int V4l2SourceConfig::cameraWidth() const {
  if (mode != V4l2Mode::kSideBySide) return width;
  if (pixelFormatFromName(pixel_format) == PixelFormat::kY8i) return width;
  return width / 2;
}

}  // namespace cblox
