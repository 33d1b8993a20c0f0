#pragma once

// V4L2 cameras as a FrameSource: one camera, a depth node, a two-camera stereo pair or a
// side-by-side stereo camera (or one interleaving its views, Y8I); bad frames dropped and
// counted; devices that disappear are reopened with exponential back-off.

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "drivers/calibration/stereo_rectifier.h"
#include "drivers/frame_source.h"
#include "drivers/camera/drop_counter.h"
#include "drivers/camera/reopen_schedule.h"
#include "drivers/camera/stereo_pairer.h"
#include "drivers/camera/timestamp_mapping.h"
#include "drivers/v4l2/v4l2_device.h"
#include "drivers/v4l2/v4l2_source_config.h"

namespace cblox {

/// Counters of a V4l2Source. Plain value type.
struct V4l2Stats {
  int64_t frames = 0;  ///< delivered by next()
  /// Dropped frames by kind: "corrupt" (V4L2_BUF_FLAG_ERROR), the conversion errors
  /// ("short_buffer", "bad_size", "bad_stride", "decode_failed", "unsupported"), "stall" (no
  /// frame within frame_timeout_s), "left_unpaired", "right_unpaired", "out_of_order".
  std::map<std::string, int64_t, std::less<>> dropped;
  int64_t device_lost = 0;      ///< times the devices were found gone (or stalled for good)
  int64_t reopen_attempts = 0;  ///< reopen attempts, failed or not
  StereoPairerStats pairing;    ///< kStereoPair only
};

/// Streams V4L2 devices as CaptureFrames (see V4l2SourceConfig and V4l2Mode):
///   timestamp_ns  the kernel's buffer timestamp (CLOCK_MONOTONIC) mapped to the system
///                 clock (CLOCK_REALTIME); the dequeue time for drivers without monotonic
///                 timestamps; for a pair, the left camera's.
///   frame_id      the driver's sequence number (of the left camera), offset so that ids keep
///                 increasing across reopens; gaps are frames the driver or we dropped.
///   images        kMono: left (+ color); kDepth: depth; kStereoPair, kSideBySide: left and
///                 right, rectified by the StereoRectifier when one is given, else raw.
/// next() blocks until a frame is delivered or frame_timeout_s passes. Bad frames (driver
/// error flag, conversion failure, unpaired) are dropped, counted by kind and the first of
/// each kind logged to stderr, and next() goes on with the following frame; next() returns
/// kError for a stall (no frame within frame_timeout_s), a lost device, and while reopening
/// (blocking at most ~1 s per call, with the status text of health()). It never returns kEnd.
/// Thread-safety: one thread calls next(); stats() and health() may be called from any
/// thread concurrently.
class V4l2Source : public FrameSource {
 public:
  /// Validates `config`, opens and configures the devices (setting exposure and gain if
  /// given) and starts streaming. `rectifier` (may be null) is used in the stereo modes: its
  /// raw resolution must be the per-camera frame size (config.cameraWidth() x height: half
  /// the frame side by side, the whole frame for Y8I), and its rectified() calibration
  /// becomes SourceInfo::stereo; without it frames carry the raw pair and SourceInfo::stereo
  /// is unset. Returns nullptr with a message in *error (if non-null) when the config is
  /// invalid, the rectifier does not fit, or a device cannot be opened or configured
  /// (V4l2Device's messages) — no reopening is tried at startup.
  static std::unique_ptr<V4l2Source> open(const V4l2SourceConfig& config,
                                          std::shared_ptr<const StereoRectifier> rectifier,
                                          std::string* error);

  ~V4l2Source() override;

  const SourceInfo& info() const override { return info_; }
  Status next(CaptureFrame* frame, std::string* error) override;

  /// Counters so far. Thread-safe.
  V4l2Stats stats() const;

  /// One line for a heartbeat: "streaming /dev/video0: 1234 frames, dropped corrupt=2" or
  /// "reopening /dev/video0 (attempt 3, next in 4 s)". Thread-safe.
  std::string health() const override;

 private:
  /// A converted image of one camera of a pair, waiting for its partner.
  struct PendingImage {
    GrayImage image;
    int64_t timestamp_ns = 0;
    uint32_t sequence = 0;
  };

  V4l2Source(V4l2SourceConfig config, std::shared_ptr<const StereoRectifier> rectifier);

  bool openDevices(std::string* error);
  void closeDevices();
  Status deviceLost(const std::string& why, std::string* error);
  Status reopen(std::string* error);
  Status stall(std::string* error);
  Status nextSingle(CaptureFrame* frame, std::string* error);
  Status nextPair(CaptureFrame* frame, std::string* error);
  /// Dequeues a frame of device `side` (0 left, 1 right) and hands it to the pairer.
  /// Returns false (with the status in *status) when the device is lost or fails.
  bool readPairSide(int side, Status* status, std::string* error);
  int64_t frameTimestampNs(const V4l2Frame& frame);
  int64_t frameId(uint32_t sequence);
  void drop(std::string_view kind, const std::string& message);
  /// Puts a stereo pair into *frame, rectified if there is a rectifier. Returns false with
  /// a message when rectification fails.
  bool fillStereo(GrayImage left, GrayImage right, CaptureFrame* frame, std::string* why) const;

  V4l2SourceConfig config_;
  PixelFormat format_ = PixelFormat::kYuyv;
  std::shared_ptr<const StereoRectifier> rectifier_;
  SourceInfo info_;
  std::vector<std::unique_ptr<V4l2Device>> devices_;
  MonotonicClockMapping clock_;
  StereoPairer pairer_;
  std::map<uint64_t, PendingImage> pending_[2];
  std::deque<std::pair<PendingImage, PendingImage>> ready_;  // paired, not yet delivered
  uint64_t next_pending_id_ = 0;
  int consecutive_stalls_ = 0;
  int64_t last_frame_id_ = -1;
  std::optional<int64_t> sequence_offset_;
  std::optional<uint32_t> last_sequence_;

  mutable std::mutex mutex_;  // guards the members below (read by stats() and health())
  DropCounter drops_;
  ReopenSchedule schedule_;
  V4l2Stats counters_;
  std::string last_loss_;
};

}  // namespace cblox
