#include "drivers/libcamera/libcamera_source_config.h"

#include <cmath>

namespace cblox {
namespace {

bool positive(double value) { return std::isfinite(value) && value > 0.0; }

}  // namespace

std::string_view libcameraStereoModeName(LibcameraStereoMode mode) {
  return mode == LibcameraStereoMode::kMono ? "mono" : "side_by_side";
}

std::optional<LibcameraStereoMode> parseLibcameraStereoMode(std::string_view name) {
  if (name == "mono") return LibcameraStereoMode::kMono;
  if (name == "side_by_side" || name == "side-by-side") return LibcameraStereoMode::kSideBySide;
  return std::nullopt;
}

std::string LibcameraSourceConfig::validate() const {
  if (std::string invalid = camera.validate(); !invalid.empty()) return "camera." + invalid;
  const bool side_by_side = mode == LibcameraStereoMode::kSideBySide;
  if (side_by_side && camera.width % 2 != 0) {
    return "side_by_side needs an even width (two halves), got " + std::to_string(camera.width);
  }
  if (rectifier != nullptr) {
    if (!side_by_side) return "a rectifier needs mode side_by_side (a mono camera has no pair)";
    const PinholeIntrinsics& raw = rectifier->raw().left.intrinsics;
    if (raw.width != camera.width / 2 || raw.height != camera.height) {
      return "the rectifier's calibration (" + rectifier->raw().source + ") is for " +
             std::to_string(raw.width) + "x" + std::to_string(raw.height) +
             " images, but the side-by-side frame " + std::to_string(camera.width) + "x" +
             std::to_string(camera.height) + " has halves of " + std::to_string(camera.width / 2) +
             "x" + std::to_string(camera.height);
    }
  }
  if (!positive(stall_timeout_s)) {
    return "stall_timeout_s must be finite and > 0, got " + std::to_string(stall_timeout_s);
  }
  if (!positive(restart_backoff_s)) {
    return "restart_backoff_s must be finite and > 0, got " + std::to_string(restart_backoff_s);
  }
  if (!std::isfinite(restart_backoff_max_s) || restart_backoff_max_s < restart_backoff_s) {
    return "restart_backoff_max_s must be finite and >= restart_backoff_s (" +
           std::to_string(restart_backoff_s) + "), got " + std::to_string(restart_backoff_max_s);
  }
  return {};
}

}  // namespace cblox
