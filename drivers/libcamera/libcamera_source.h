#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>

#include "core/geometry/image.h"
#include "drivers/frame_source.h"
#include "drivers/libcamera/libcamera_camera.h"
#include "drivers/libcamera/libcamera_source_config.h"
#include "drivers/camera/drop_counter.h"
#include "drivers/camera/reopen_schedule.h"
#include "drivers/camera/timestamp_mapping.h"

namespace cblox {

/// A libcamera camera as a capture source: each frame becomes a CaptureFrame with
/// `frame_id` from the camera's frame counter (gaps where it dropped frames; kept increasing
/// across restarts), `timestamp_ns` on the system clock (SensorTimestamp, CLOCK_MONOTONIC,
/// mapped by the current clock offset), and grey `left` (mono) or `left` and `right`
/// (side-by-side, rectified when the config has a rectifier). The pixels are converted by
/// drivers/pixel (toGray, splitSideBySide).
///
/// Bad frames (a request cancelled, a frame error, a conversion or rectification failure) are
/// skipped and counted by kind (DropCounter: the first of each kind is reported on stderr);
/// next() waits for the following frame. A camera that completes no request for
/// stall_timeout_s, is unplugged, or cannot queue a request is closed and next() returns
/// kError with the reason; the following next() reopens it after the back-off (see
/// LibcameraSourceConfig), returning kError again while reopening fails.
///
/// Thread-safety: next() from one thread (FrameSource's contract); health() and dropCounts()
/// from any thread at any time.
class LibcameraSource : public FrameSource {
 public:
  /// Validates `config`, opens and starts the camera. Returns nullptr and a message in
  /// *error (if non-null) when the config is invalid ("libcamera source: <validate()>") or
  /// the camera cannot be opened or started (LibcameraCamera::open()'s and start()'s
  /// messages; e.g. "libcamera camera 'imx219' not found; cameras present: none").
  /// Thread-safe.
  static std::unique_ptr<LibcameraSource> open(const LibcameraSourceConfig& config,
                                               std::string* error);

  ~LibcameraSource() override;

  /// name "libcamera:<camera id>"; rate_hz the config's (0 = the camera's own, unknown);
  /// stereo the rectifier's rectified() calibration when there is one; no depth; notes: the
  /// stream format, unset controls (LibcameraCamera::warnings()), raw side-by-side halves.
  const SourceInfo& info() const override { return info_; }

  /// Delivers the next good frame (kFrame); never kEnd (a camera does not end); kError
  /// with a message starting with "libcamera:<id>: " on a stall, a disconnection, a failed
  /// re-queue, a failed restart, or stall_timeout_s of bad frames only (counted, see the
  /// class comment). Blocks up to the back-off plus stall_timeout_s.
  Status next(CaptureFrame* frame, std::string* error) override;

  /// One line for the heartbeat, e.g. "libcamera:imx219 streaming YUYV (libcamera YUYV)
  /// 640x480 stride 1280, 4 buffers; 1200 frames; dropped frame_error=2; 0 restarts", or
  /// "reopening libcamera:imx219 (attempt 2, next in 2 s) YUYV ... (last error: ...)".
  /// Thread-safe.
  std::string health() const override;

  /// Bad frames and failures by kind: "request_cancelled", "frame_error", "frame_cancelled",
  /// "no_buffer", "convert_<convertErrorName>", "rectify", "stall", "disconnected",
  /// "queue_error", "restart_failed". Thread-safe.
  std::map<std::string, int64_t, std::less<>> dropCounts() const;

 private:
  using Clock = std::chrono::steady_clock;

  LibcameraSource(const LibcameraSourceConfig& config, std::unique_ptr<LibcameraCamera> camera);
  bool reopen(std::string* error);
  Status fail(const std::string& kind, const std::string& message, std::string* error);
  void countDrop(std::string_view kind, const std::string& message);
  bool convert(const LibcameraFrame& raw, CaptureFrame* frame, std::string* kind,
               std::string* message);
  int64_t frameIdOf(uint32_t sequence);

  const LibcameraSourceConfig config_;
  const std::string name_;  // "libcamera:<id>"
  std::unique_ptr<LibcameraCamera> camera_;
  SourceInfo info_;
  MonotonicClockMapping clock_;

  // Frame ids: camera sequence + base, rebased when a (restarted) camera counts from 0.
  bool have_base_ = false;
  int64_t sequence_base_ = 0;
  int64_t next_frame_id_ = 0;

  // Restarts: attempt k is due restart_backoff_s * 2^(k-1) (at most restart_backoff_max_s)
  // after the failure before it; back to connected when a frame is delivered again.
  ReopenSchedule restart_;

  GrayImage both_, left_raw_, right_raw_;  // side-by-side scratch

  mutable std::mutex stats_mutex_;  // guards the fields below (read by health())
  DropCounter drops_;
  int64_t frames_ = 0;
  int64_t restarts_ = 0;
  std::string state_;  // "streaming" or restart_.status(): "reopening <name> (attempt ...)"
  std::string last_error_;
  std::string format_text_;
};

}  // namespace cblox
