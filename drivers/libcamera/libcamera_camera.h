#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <libcamera/camera.h>
#include <libcamera/camera_manager.h>
#include <libcamera/controls.h>
#include <libcamera/framebuffer_allocator.h>
#include <libcamera/request.h>
#include <libcamera/stream.h>

#include "drivers/libcamera/completed_request_queue.h"
#include "drivers/libcamera/libcamera_camera_config.h"
#include "drivers/libcamera/mapped_frame_buffer.h"
#include "drivers/pixel/raw_image.h"

namespace cblox {

/// The stream a LibcameraCamera was configured with. Plain value type.
struct LibcameraStreamFormat {
  libcamera::PixelFormat libcamera_format;  ///< as configured (e.g. formats::YUYV)
  PixelFormat format = PixelFormat::kGrey;  ///< the same bytes as a cblox layout
  int width = 0;
  int height = 0;
  size_t stride = 0;              ///< bytes per row of the first plane; 0 for MJPEG
  unsigned int buffer_count = 0;  ///< buffers (= requests) allocated

  /// E.g. "YUYV (libcamera YUYV) 640x480 stride 1280, 4 buffers". Thread-safe.
  std::string describe() const;
};

/// One frame borrowed from a completed request; valid only while the consumer passed to
/// LibcameraCamera::waitFrame() runs (the buffer is queued again right after).
struct LibcameraFrame {
  RawImage image;                 ///< the frame's bytes (see assembleRawImage)
  uint32_t sequence = 0;          ///< the camera's frame counter (FrameMetadata::sequence)
  int64_t monotonic_ns = 0;       ///< CLOCK_MONOTONIC capture time
  bool sensor_timestamp = false;  ///< from the SensorTimestamp control (else the buffer's)
};

/// One libcamera camera streaming one stream, by libcamera's request cycle: a request per
/// buffer, all queued at start(); libcamera's requestCompleted signal (on its own thread)
/// hands each completed request to a queue; waitFrame() takes it, gives its frame to the
/// caller, and queues it again (Request::reuse(ReuseBuffers)).
///
/// Lifecycle: open() = start the process's CameraManager (sharedCameraManager), find the
/// camera, acquire it, configure the stream, allocate and mmap the buffers, create the
/// requests and the controls; start(); waitFrame()...; stop() (may start() again);
/// destruction = stop(), disconnect the signals, free the requests, buffers and mappings,
/// release the camera, and drop the manager (stopped with its last user).
///
/// Thread-safety: not thread-safe; one thread calls every member. (libcamera's thread only
/// enters through the internal queue.)
class LibcameraCamera {
 public:
  /// Opens and configures the camera of `config` (not started). Returns nullptr and a
  /// message in *error (if non-null) when:
  /// - the config is invalid (its validate() message);
  /// - the camera manager cannot start;
  /// - the camera is not found: "libcamera camera '<id>' not found; cameras present: <list
  ///   or none>";
  /// - it is busy: "libcamera camera '<id>' is busy (in use by another program or source)",
  ///   or cannot be acquired for another reason;
  /// - it has no configuration for video (VideoRecording, else Viewfinder role);
  /// - it cannot deliver the asked format and size: validate() rejects the configuration or
  ///   adjusts the format or the size; the message names the camera, what was asked, what
  ///   libcamera proposed, and every format the camera offers with its sizes;
  /// - a control value lies outside the camera's range (ExposureTime, AnalogueGain: the
  ///   message gives the range);
  /// - configure(), buffer allocation, mmap of a buffer or request creation fails.
  /// Controls the camera does not have (FrameDurationLimits for rate_hz, ExposureTime,
  /// AnalogueGain) are skipped with a message in warnings(); a raised buffer count too.
  /// Thread-safe (the manager is shared under a lock).
  static std::unique_ptr<LibcameraCamera> open(const LibcameraCameraConfig& config,
                                               std::string* error);

  ~LibcameraCamera();
  LibcameraCamera(const LibcameraCamera&) = delete;
  LibcameraCamera& operator=(const LibcameraCamera&) = delete;

  /// The camera's libcamera id.
  const std::string& id() const { return id_; }

  /// The configured stream.
  const LibcameraStreamFormat& format() const { return format_; }

  /// What open() could not set as asked (one sentence each, naming the camera).
  const std::vector<std::string>& warnings() const { return warnings_; }

  /// True between a successful start() and stop().
  bool running() const { return running_; }

  /// Starts the camera with the controls of the config and queues every request. Returns
  /// true at once when already running. Returns false and a message naming the camera and
  /// libcamera's error in *error (if non-null) when Camera::start() or queueing fails (the
  /// camera is then stopped again).
  bool start(std::string* error);

  /// Stops the camera: pending requests complete as cancelled and are forgotten. No-op when
  /// not running. Never fails.
  void stop();

  enum class WaitStatus {
    kFrame,         ///< a frame was handed to the consumer
    kDropped,       ///< a request completed without a usable frame; `drop_kind` says why
    kTimeout,       ///< no request completed within the timeout
    kDisconnected,  ///< the camera went away (unplugged); stop and reopen
    kError,         ///< not running, or a request could not be queued again; `message`
  };
  struct WaitResult {
    WaitStatus status = WaitStatus::kTimeout;
    /// For kDropped: "request_cancelled" (Request::RequestCancelled), "frame_error"
    /// (FrameMetadata::FrameError), "frame_cancelled" (FrameMetadata::FrameCancelled) or
    /// "no_buffer" (the request holds no buffer of the stream).
    std::string drop_kind;
    std::string message;  ///< for kDisconnected and kError, naming the camera
  };

  /// Waits up to `timeout` for a completed request. A good frame is passed to `consume`
  /// (called on this thread; the frame's bytes are valid only during the call), then the
  /// request is queued again whatever happened (also when `consume` throws, which
  /// propagates). A request that completed without a frame is queued again and reported as
  /// kDropped. Time stamps come from the SensorTimestamp metadata control, else the
  /// buffer's FrameMetadata::timestamp (both CLOCK_MONOTONIC).
  WaitResult waitFrame(std::chrono::nanoseconds timeout,
                       const std::function<void(const LibcameraFrame&)>& consume);

 private:
  LibcameraCamera() = default;

  bool configureStream(const LibcameraCameraConfig& config, std::string* error);
  bool setUpControls(const LibcameraCameraConfig& config, std::string* error);
  bool allocateBuffers(std::string* error);
  void onRequestCompleted(libcamera::Request* request);
  void onDisconnected();

  // Declared in the order of acquisition; the destructor releases in reverse.
  std::shared_ptr<libcamera::CameraManager> manager_;
  std::shared_ptr<libcamera::Camera> camera_;
  bool acquired_ = false;
  bool signals_connected_ = false;
  std::unique_ptr<libcamera::CameraConfiguration> configuration_;
  libcamera::Stream* stream_ = nullptr;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator_;
  std::vector<MappedFrameBuffer> mappings_;  // by request cookie (= buffer index)
  std::vector<std::unique_ptr<libcamera::Request>> requests_;
  libcamera::ControlList controls_;  // applied at start() and on the first requests
  CompletedRequestQueue completed_;
  bool running_ = false;

  std::string id_;
  LibcameraStreamFormat format_;
  std::vector<std::string> warnings_;
  std::vector<uint8_t> scratch_;  // gathered planes (assembleRawImage)
};

}  // namespace cblox
