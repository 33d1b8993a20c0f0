#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "drivers/calibration/stereo_rectifier.h"
#include "drivers/libcamera/libcamera_camera_config.h"

namespace cblox {

/// How a libcamera frame becomes the grey images of a CaptureFrame.
enum class LibcameraStereoMode {
  kMono,        ///< the whole frame is `left`
  kSideBySide,  ///< a stereo camera's frame: left half `left`, right half `right`
};

/// "mono" or "side_by_side". Thread-safe (pure).
std::string_view libcameraStereoModeName(LibcameraStereoMode mode);

/// Parses "mono" or "side_by_side" (also "side-by-side"); std::nullopt otherwise.
/// Thread-safe (pure).
std::optional<LibcameraStereoMode> parseLibcameraStereoMode(std::string_view name);

/// Settings of a LibcameraSource. Plain value type (the rectifier is shared and immutable);
/// check it with validate().
struct LibcameraSourceConfig {
  /// The camera and its stream: id, pixel format, width x height (the whole side-by-side
  /// frame), rate_hz, buffer_count, exposure_us, analogue_gain.
  LibcameraCameraConfig camera;
  LibcameraStereoMode mode = LibcameraStereoMode::kMono;
  /// Side-by-side only, optional: rectifies each raw pair (its raw resolution must be half
  /// the frame's width by its height); the source's info().stereo is then its rectified()
  /// calibration. Without it the halves are delivered raw and info().stereo is empty.
  std::shared_ptr<const StereoRectifier> rectifier;
  /// A camera that completes no request for this long is stalled: next() returns kError and
  /// the camera is closed and reopened.
  double stall_timeout_s = 2.0;
  /// Wait before the first reopening after a failure; doubled after each failed attempt up
  /// to restart_backoff_max_s, reset by a delivered frame.
  double restart_backoff_s = 1.0;
  double restart_backoff_max_s = 30.0;

  /// Returns "" when usable, else a message naming the first bad field: camera's
  /// validate() ("camera.<its message>"); side_by_side with an odd width; a rectifier with
  /// mode mono, or whose raw resolution is not (width / 2) x height; stall_timeout_s not
  /// finite or <= 0; restart_backoff_s not finite or <= 0; restart_backoff_max_s below
  /// restart_backoff_s or not finite. Thread-safe (pure).
  std::string validate() const;
};

}  // namespace cblox
