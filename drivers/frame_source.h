#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"
#include "core/geometry/stereo_rig.h"

namespace cblox {

/// What a capture source delivers and how it is calibrated. The source's primary camera C is
/// the rectified left camera when the source has stereo, else the depth camera. Plain value.
struct SourceInfo {
  std::string name;      ///< e.g. "sim:room/loop", "euroc:/data/V1_01/mav0"
  double rate_hz = 0.0;  ///< nominal frame rate; 0 when unknown
  /// A live camera: frames come at their own pace, and a player never waits for their time
  /// stamps (cblox-capture's `rate` applies to recorded and simulated sources only).
  bool live = false;
  /// Present when frames carry a rectified stereo pair.
  std::optional<RectifiedStereoCalibration> stereo;
  /// Present when frames carry a depth image (and, if colour is delivered, a colour image
  /// registered to it).
  std::optional<PinholeIntrinsics> depth_intrinsics;
  /// Depth camera D in the primary camera C (identity when D is C).
  Transformationd T_C_D;
  double depth_min_m = 0.0;   ///< valid depth range of the depth images
  double depth_max_m = 0.0;
  std::optional<size_t> frame_count;  ///< frames the source will try to deliver, if known
  bool has_ground_truth = false;      ///< frames carry T_G_C
  /// Human-readable remarks: skipped files, missing ground truth, defaults used.
  std::vector<std::string> notes;
};

/// One capture: images of the same instant, with the exact pose when the source knows it.
/// Images a source does not deliver are empty. Plain value type.
struct CaptureFrame {
  /// Sequence number of the frame at the source (0, 1, 2, ...). Frames the source dropped
  /// leave gaps, as a camera's hardware counter would.
  int64_t frame_id = 0;
  int64_t timestamp_ns = 0;  ///< capture time (dataset or simulated clock)
  GrayImage left, right;     ///< rectified stereo pair
  DepthImage depth;          ///< metres along the depth camera's z; 0 = no measurement
  ColorImage color;          ///< registered to `depth`
  std::optional<Transformationd> T_G_C;  ///< ground-truth pose of the primary camera
};

/// A capture back end: simulator, dataset reader, camera driver. Delivers frames in order.
/// Thread-safety: not thread-safe; one thread calls next().
class FrameSource {
 public:
  enum class Status { kFrame, kEnd, kError };

  virtual ~FrameSource() = default;

  /// Calibration and description; valid for the source's lifetime.
  virtual const SourceInfo& info() const = 0;

  /// Delivers the next frame into *frame (kFrame); kEnd once there is none left; kError with
  /// a message naming the file or cause when this frame cannot be delivered (the caller may
  /// call next() again to go on with the following frame).
  virtual Status next(CaptureFrame* frame, std::string* error) = 0;

  /// One line on the state of a live device for the heartbeat and the log, e.g. "streaming
  /// /dev/video0: 1234 frames" or "reopening /dev/video0 (attempt 3, next in 4 s)"; empty for
  /// sources that are not devices (simulator, datasets).
  /// Thread-safe: may be called from any thread while another calls next().
  virtual std::string health() const { return {}; }
};

}  // namespace cblox
