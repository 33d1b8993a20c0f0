#pragma once

// Configuration of V4l2Source: which devices, in which arrangement, at which format.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"

namespace cblox {

/// How the V4L2 devices make up a frame.
enum class V4l2Mode {
  kMono,        ///< one camera: CaptureFrame::left (grey), and colour if asked
  kDepth,       ///< one depth node (Z16): CaptureFrame::depth
  kStereoPair,  ///< two cameras, left and right, paired by timestamp: left, right
  kSideBySide,  ///< one camera delivering both views in each frame: left, right; side by side
                ///< (two halves), or interleaved for pixel format Y8I (two full-width views)
};

/// "mono", "depth", "stereo_pair", "side_by_side". Thread-safe (pure).
std::string_view v4l2ModeName(V4l2Mode mode);
/// Parses v4l2ModeName()'s names; std::nullopt otherwise. Thread-safe (pure).
std::optional<V4l2Mode> v4l2ModeFromName(std::string_view name);

/// Options of V4l2Source. Plain value type.
struct V4l2SourceConfig {
  /// Device nodes: one, or two (left, right) for kStereoPair.
  std::vector<std::string> devices = {"/dev/video0"};
  V4l2Mode mode = V4l2Mode::kMono;
  /// A name pixelFormatFromName() parses: "YUYV", "MJPEG", "GREY", "Z16", ...
  std::string pixel_format = "YUYV";
  int width = 640;  ///< of the device frame (both views for kSideBySide; cameraWidth())
  int height = 480;
  double rate_hz = 30.0;  ///< requested; 0 keeps the driver's
  int buffer_count = 4;   ///< mmap buffers per device, 2..32
  /// kStereoPair: largest |t_right - t_left| of a pair (ms, > 0). Keep it below half the
  /// frame interval.
  double pair_tolerance_ms = 5.0;
  /// exposure_absolute in the driver's unit (100 us for UVC); setting it switches
  /// exposure_auto to manual first. Unset keeps the camera's setting.
  std::optional<int> exposure;
  std::optional<int> gain;  ///< unset keeps the camera's setting
  /// kDepth: metres per depth unit (0.001 for Intel RealSense Z16), > 0.
  double depth_scale_m = 0.001;
  /// kDepth: the depth camera's intrinsics (V4L2 does not tell); SourceInfo::depth_intrinsics.
  std::optional<PinholeIntrinsics> depth_intrinsics;
  /// kDepth: the depth camera D in the rig's body frame B, the frame the tracker's poses are
  /// of (with a Kalibr camchain without T_cam_imu: the stereo pair's raw left camera), for a
  /// depth camera beside a stereo pair run by another cblox-capture; SourceInfo::T_C_D.
  Transformationd T_B_D;
  double depth_min_m = 0.1;  ///< kDepth: valid range, SourceInfo::depth_min_m / max_m
  double depth_max_m = 10.0;
  bool color = false;  ///< kMono: also convert to CaptureFrame::color
  /// A device that disappears is reopened after reopen_min_s, then at doubling intervals up
  /// to reopen_max_s (0 < min <= max).
  double reopen_min_s = 1.0;
  double reopen_max_s = 30.0;
  /// No deliverable frame for this long (s, > 0) is a stall: next() reports it; after
  /// stalls_before_reopen (>= 1) stalls in a row the devices are closed and reopened.
  double frame_timeout_s = 2.0;
  int stalls_before_reopen = 3;

  /// Returns "" if usable, else a message naming the first bad field (device count for the
  /// mode, unknown or mode-incompatible pixel format: Z16 only in kDepth, Y8I only in
  /// kSideBySide; sizes, with an even width for kSideBySide except Y8I; rate, counts,
  /// tolerance, depth scale and range, intrinsics size vs. the frame, back-off and timeouts).
  /// Thread-safe (pure).
  std::string validate() const;

  /// Width of one camera's image: width / 2 for kSideBySide (two halves side by side), but
  /// the full width for kSideBySide with pixel format Y8I (interleaved: each view is as wide
  /// as the frame) and for the other modes. Thread-safe (pure).
  int cameraWidth() const;
};

}  // namespace cblox
