#pragma once

// One V4L2 video capture device (a /dev/videoN node) streaming through memory-mapped
// buffers, via libv4l2 (which also offers software-converted formats for odd cameras).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "drivers/pixel/raw_image.h"
#include "drivers/v4l2/v4l2_controls.h"
#include "drivers/v4l2/v4l2_formats.h"

namespace cblox {

/// Outcome of V4l2Device::dequeue().
enum class V4l2Status {
  kOk,          ///< a frame was dequeued
  kTimeout,     ///< no frame within the timeout (or the wait was interrupted by a signal)
  kDeviceLost,  ///< the device is gone (ENODEV, ENXIO, EIO, POLLERR): close and reopen it
  kError,       ///< any other failure; the message says which call failed
};

/// What configure() asks of the device. Plain value type.
struct V4l2StreamConfig {
  PixelFormat format = PixelFormat::kYuyv;
  int width = 640;
  int height = 480;
  double rate_hz = 0.0;  ///< 0 keeps the driver's rate
  int buffer_count = 4;  ///< buffers to request, 2..32 (the driver may grant more)
};

/// One dequeued frame. `image` borrows the device's buffer: valid until requeue(), the next
/// dequeue() or the device's destruction. Plain value type.
struct V4l2Frame {
  RawImage image;            ///< format, size and stride from configure(); bytes = bytesused
  int64_t timestamp_ns = 0;  ///< the buffer's timestamp
  bool timestamp_monotonic = false;  ///< V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC: CLOCK_MONOTONIC
  uint32_t sequence = 0;             ///< the driver's frame counter (gaps = frames it dropped)
  uint32_t flags = 0;                ///< V4L2_BUF_FLAG_*
  bool corrupt = false;              ///< V4L2_BUF_FLAG_ERROR: the driver saw a transfer error
  uint32_t buffer_index = 0;
};

/// An open V4L2 capture device. Lifecycle: open() -> configure() (streams) -> dequeue() /
/// requeue() ... -> destructor (STREAMOFF, munmap, free the buffers, close). Once a call
/// reports the device lost, every later dequeue() reports kDeviceLost: destroy and reopen.
/// Not thread-safe: one thread uses a device.
class V4l2Device {
 public:
  /// Opens `path` and checks that it is a V4L2 video capture device with streaming I/O.
  /// Returns nullptr and a message starting with the path in *error (if non-null) when:
  /// it does not exist ("/dev/video3: no such device"); it is busy ("/dev/video3 is busy
  /// (used by another process?)"); permission is denied; it answers no VIDIOC_QUERYCAP
  /// ("/dev/null: not a V4L2 device (...)"); it cannot capture video (e.g. a UVC metadata
  /// node) or only through the multi-planar API; it has no streaming I/O.
  static std::unique_ptr<V4l2Device> open(const std::string& path, std::string* error);

  ~V4l2Device();
  V4l2Device(const V4l2Device&) = delete;
  V4l2Device& operator=(const V4l2Device&) = delete;

  const std::string& path() const { return path_; }
  /// VIDIOC_QUERYCAP's card, driver and bus_info, e.g. "HD Pro Webcam C920", "uvcvideo".
  const std::string& card() const { return card_; }
  const std::string& driver() const { return driver_; }
  const std::string& busInfo() const { return bus_info_; }
  /// The file descriptor, for poll() over several devices (POLLIN: a frame is ready).
  int fd() const { return fd_; }

  /// Lists the formats, sizes and rates (VIDIOC_ENUM_FMT, ENUM_FRAMESIZES,
  /// ENUM_FRAMEINTERVALS) into *formats (non-null). Returns false with a message naming the
  /// device when VIDIOC_ENUM_FMT fails for a reason other than the end of the list.
  bool listFormats(std::vector<V4l2FormatInfo>* formats, std::string* error) const;

  /// describeFormats() of listFormats(), or its error message.
  std::string describeFormats() const;

  /// Sets the format (VIDIOC_S_FMT) and rate (VIDIOC_S_PARM), maps `buffer_count` buffers,
  /// queues them and starts streaming; stops a previous stream first. Returns false, not
  /// streaming, with a message naming the device when: the request is invalid; the device is
  /// busy; the driver changes the format or size (the message names the request and what the
  /// driver chose, and lists the formats it offers); the driver sets another rate (> 1% off;
  /// a driver without rate control keeps its own, see rateHz()); fewer than 2 buffers are
  /// granted; mapping or STREAMON fails.
  bool configure(const V4l2StreamConfig& config, std::string* error);

  /// The configured stream; valid after a successful configure().
  const V4l2StreamConfig& config() const { return config_; }
  /// Bytes per row the driver reported (0 for compressed formats).
  size_t stride() const { return stride_; }
  /// The frame rate the driver reports (VIDIOC_G_PARM), 0 when it does not say.
  double rateHz() const { return rate_hz_; }
  /// Buffers granted by VIDIOC_REQBUFS.
  size_t bufferCount() const { return buffers_.size(); }
  bool streaming() const { return streaming_; }
  /// True once a call found the device gone.
  bool lost() const { return lost_; }

  /// Waits up to timeout_ms (>= 0) for a frame and dequeues it into *frame (non-null); a
  /// frame still held from the previous call is requeued first. Returns kOk, kTimeout,
  /// kDeviceLost or kError with a message naming the device in *error (if non-null).
  /// Frames the driver flags V4L2_BUF_FLAG_ERROR come back kOk with frame->corrupt set.
  V4l2Status dequeue(int timeout_ms, V4l2Frame* frame, std::string* error);

  /// Gives the held frame's buffer back to the driver (a no-op if none is held). Returns
  /// false with a message if VIDIOC_QBUF fails (the device may then be lost()).
  bool requeue(std::string* error);

  /// Sets a control by name (controlIdFromName) after checking it with VIDIOC_QUERYCTRL.
  /// Returns false with a message naming the device and control when the name is unknown,
  /// the device lacks the control (or it is disabled or read-only), the value is out of its
  /// range or off its step, or VIDIOC_S_CTRL fails (e.g. exposure_absolute while
  /// exposure_auto is not manual).
  bool setControl(std::string_view name, int64_t value, std::string* error);

  /// The range of a control by name, or std::nullopt with a message as setControl's.
  std::optional<V4l2ControlRange> queryControl(std::string_view name, std::string* error) const;

 private:
  struct Buffer {
    void* start = nullptr;
    size_t length = 0;
  };

  V4l2Device(std::string path, int fd) : path_(std::move(path)), fd_(fd) {}

  int ioctl(unsigned long request, void* arg) const;
  std::string failure(const std::string& call, int err) const;
  bool noteLoss(int err);
  void stopStreaming();

  std::string path_;
  int fd_ = -1;
  std::string card_, driver_, bus_info_;
  V4l2StreamConfig config_;
  size_t stride_ = 0;
  double rate_hz_ = 0.0;
  std::vector<Buffer> buffers_;
  bool streaming_ = false;
  bool lost_ = false;
  std::optional<uint32_t> held_;
};

}  // namespace cblox
