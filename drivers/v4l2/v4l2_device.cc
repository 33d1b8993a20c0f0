#include "drivers/v4l2/v4l2_device.h"

#include <fcntl.h>
#include <libv4l2.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>

#include "drivers/pixel/pixel_format.h"
#include "drivers/camera/timestamp_mapping.h"

namespace cblox {
namespace {

std::string errnoText(int err) { return std::strerror(err); }

bool isLoss(int err) { return err == ENODEV || err == ENXIO || err == EIO; }

std::string fixedString(const uint8_t* text, size_t size) {
  return std::string(reinterpret_cast<const char*>(text),
                     strnlen(reinterpret_cast<const char*>(text), size));
}

std::string describeRequest(PixelFormat format, int width, int height) {
  return std::string(pixelFormatName(format)) + " " + std::to_string(width) + "x" +
         std::to_string(height);
}

double rateOfInterval(const v4l2_fract& interval) {
  if (interval.numerator == 0) return 0.0;
  return static_cast<double>(interval.denominator) / static_cast<double>(interval.numerator);
}

}  // namespace

int V4l2Device::ioctl(unsigned long request, void* arg) const {
  int result;
  do {
    result = v4l2_ioctl(fd_, request, arg);
  } while (result == -1 && errno == EINTR);
  return result;
}

std::string V4l2Device::failure(const std::string& call, int err) const {
  if (err == EBUSY) return path_ + " is busy (used by another process?): " + call + " failed";
  if (isLoss(err)) return path_ + ": device lost (" + call + ": " + errnoText(err) + ")";
  return path_ + ": " + call + " failed: " + errnoText(err);
}

bool V4l2Device::noteLoss(int err) {
  if (isLoss(err)) lost_ = true;
  return lost_;
}

std::unique_ptr<V4l2Device> V4l2Device::open(const std::string& path, std::string* error) {
  auto fail = [&](const std::string& message) {
    if (error) *error = message;
    return nullptr;
  };
  // A plain open() and VIDIOC_QUERYCAP first, for clear messages (libv4l2's v4l2_open would
  // print its own on stderr); then libv4l2 takes the descriptor over.
  const int fd = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    switch (err) {
      case ENOENT:
      case ENODEV:
      case ENXIO:
        return fail(path + ": no such device");
      case EBUSY:
        return fail(path + " is busy (used by another process?)");
      case EACCES:
      case EPERM:
        return fail(path + ": permission denied (is the user in the 'video' group?)");
      default:
        return fail(path + ": cannot open: " + errnoText(err));
    }
  }
  v4l2_capability cap{};
  int result;
  do {
    result = ::ioctl(fd, VIDIOC_QUERYCAP, &cap);
  } while (result == -1 && errno == EINTR);
  if (result == -1) {
    const int err = errno;
    ::close(fd);
    return fail(path + ": not a V4L2 device (VIDIOC_QUERYCAP: " + errnoText(err) + ")");
  }
  const uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
  const std::string card = fixedString(cap.card, sizeof(cap.card));
  if ((caps & V4L2_CAP_VIDEO_CAPTURE) == 0) {
    ::close(fd);
    if ((caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE) != 0) {
      return fail(path + " (" + card +
                  "): only multi-planar capture, which cblox does not support (use libcamera)");
    }
    if ((caps & V4L2_CAP_META_CAPTURE) != 0) {
      return fail(path + " (" + card +
                  "): a metadata node, not a video capture device (try the node before it)");
    }
    return fail(path + " (" + card + "): not a video capture device");
  }
  if ((caps & V4L2_CAP_STREAMING) == 0) {
    ::close(fd);
    return fail(path + " (" + card + "): no streaming I/O (read() only), not supported");
  }
  if (v4l2_fd_open(fd, 0) == -1) {
    const int err = errno;
    ::close(fd);
    return fail(path + ": libv4l2 cannot take over the device: " + errnoText(err));
  }
  std::unique_ptr<V4l2Device> device(new V4l2Device(path, fd));
  device->card_ = card;
  device->driver_ = fixedString(cap.driver, sizeof(cap.driver));
  device->bus_info_ = fixedString(cap.bus_info, sizeof(cap.bus_info));
  return device;
}

V4l2Device::~V4l2Device() {
  stopStreaming();
  if (fd_ >= 0) v4l2_close(fd_);
}

void V4l2Device::stopStreaming() {
  if (streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    ioctl(VIDIOC_STREAMOFF, &type);  // errors ignored: the device may be gone
    streaming_ = false;
  }
  held_.reset();
  for (const Buffer& buffer : buffers_) {
    if (buffer.start != nullptr) v4l2_munmap(buffer.start, buffer.length);
  }
  if (!buffers_.empty() && !lost_) {
    v4l2_requestbuffers request{};
    request.count = 0;
    request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    request.memory = V4L2_MEMORY_MMAP;
    ioctl(VIDIOC_REQBUFS, &request);
  }
  buffers_.clear();
}

bool V4l2Device::listFormats(std::vector<V4l2FormatInfo>* formats, std::string* error) const {
  formats->clear();
  for (uint32_t index = 0;; ++index) {
    v4l2_fmtdesc desc{};
    desc.index = index;
    desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (ioctl(VIDIOC_ENUM_FMT, &desc) == -1) {
      if (errno == EINVAL) break;  // end of the list
      if (error) *error = failure("VIDIOC_ENUM_FMT", errno);
      return false;
    }
    V4l2FormatInfo format;
    format.fourcc = desc.pixelformat;
    format.description = fixedString(desc.description, sizeof(desc.description));
    format.compressed = (desc.flags & V4L2_FMT_FLAG_COMPRESSED) != 0;
    format.emulated = (desc.flags & V4L2_FMT_FLAG_EMULATED) != 0;
    for (uint32_t size_index = 0;; ++size_index) {
      v4l2_frmsizeenum size{};
      size.index = size_index;
      size.pixel_format = desc.pixelformat;
      if (ioctl(VIDIOC_ENUM_FRAMESIZES, &size) == -1) break;
      V4l2FrameSize frame_size;
      if (size.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
        frame_size.width = static_cast<int>(size.discrete.width);
        frame_size.height = static_cast<int>(size.discrete.height);
      } else {
        frame_size.stepwise = true;
        frame_size.min_width = static_cast<int>(size.stepwise.min_width);
        frame_size.min_height = static_cast<int>(size.stepwise.min_height);
        frame_size.width = static_cast<int>(size.stepwise.max_width);
        frame_size.height = static_cast<int>(size.stepwise.max_height);
        frame_size.step_width = static_cast<int>(size.stepwise.step_width);
        frame_size.step_height = static_cast<int>(size.stepwise.step_height);
      }
      // Rates at the (largest) size.
      for (uint32_t rate_index = 0;; ++rate_index) {
        v4l2_frmivalenum interval{};
        interval.index = rate_index;
        interval.pixel_format = desc.pixelformat;
        interval.width = static_cast<uint32_t>(frame_size.width);
        interval.height = static_cast<uint32_t>(frame_size.height);
        if (ioctl(VIDIOC_ENUM_FRAMEINTERVALS, &interval) == -1) break;
        if (interval.type == V4L2_FRMIVAL_TYPE_DISCRETE) {
          frame_size.rates_hz.push_back(rateOfInterval(interval.discrete));
        } else {
          // The shortest interval is the highest rate.
          frame_size.max_rate_hz = rateOfInterval(interval.stepwise.min);
          frame_size.min_rate_hz = rateOfInterval(interval.stepwise.max);
          break;
        }
      }
      format.sizes.push_back(std::move(frame_size));
      if (size.type != V4L2_FRMSIZE_TYPE_DISCRETE) break;  // one range describes them all
    }
    formats->push_back(std::move(format));
  }
  return true;
}

std::string V4l2Device::describeFormats() const {
  std::vector<V4l2FormatInfo> formats;
  std::string error;
  if (!listFormats(&formats, &error)) return error;
  return cblox::describeFormats(formats);
}

bool V4l2Device::configure(const V4l2StreamConfig& config, std::string* error) {
  auto fail = [&](const std::string& message) {
    stopStreaming();
    if (error) *error = message;
    return false;
  };
  stopStreaming();
  if (lost_) return fail(path_ + ": device lost");
  const std::string request = describeRequest(config.format, config.width, config.height);
  if (config.width <= 0 || config.height <= 0 || config.width > kMaxImageSide ||
      config.height > kMaxImageSide) {
    return fail(path_ + ": invalid size in request " + request);
  }
  if (config.buffer_count < 2 || config.buffer_count > 32) {
    return fail(path_ + ": buffer count must be 2..32, got " + std::to_string(config.buffer_count));
  }
  if (!std::isfinite(config.rate_hz) || config.rate_hz < 0.0) {
    return fail(path_ + ": invalid frame rate " + std::to_string(config.rate_hz));
  }

  v4l2_format format{};
  format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  format.fmt.pix.width = static_cast<uint32_t>(config.width);
  format.fmt.pix.height = static_cast<uint32_t>(config.height);
  format.fmt.pix.pixelformat = fourccOf(config.format);
  format.fmt.pix.field = V4L2_FIELD_NONE;
  if (ioctl(VIDIOC_S_FMT, &format) == -1) {
    const int err = errno;
    noteLoss(err);
    return fail(failure("VIDIOC_S_FMT " + request, err));
  }
  const std::optional<PixelFormat> chosen = pixelFormatFromFourcc(format.fmt.pix.pixelformat);
  if (chosen != config.format || static_cast<int>(format.fmt.pix.width) != config.width ||
      static_cast<int>(format.fmt.pix.height) != config.height) {
    return fail(path_ + " (" + card_ + ") does not offer " + request + " (it chose " +
                fourccToString(format.fmt.pix.pixelformat) + " " +
                std::to_string(format.fmt.pix.width) + "x" + std::to_string(format.fmt.pix.height) +
                "); it offers:\n" + describeFormats());
  }
  if (format.fmt.pix.field != V4L2_FIELD_NONE && format.fmt.pix.field != V4L2_FIELD_ANY) {
    return fail(path_ + ": interlaced video (field order " + std::to_string(format.fmt.pix.field) +
                ") is not supported");
  }
  stride_ = config.format == PixelFormat::kMjpeg ? 0 : format.fmt.pix.bytesperline;

  // Frame rate.
  rate_hz_ = 0.0;
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  const bool has_parm = ioctl(VIDIOC_G_PARM, &parm) == 0;
  const bool settable = has_parm && (parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME) != 0;
  if (config.rate_hz > 0.0 && settable) {
    parm = v4l2_streamparm{};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    parm.parm.capture.timeperframe.numerator = 1000;
    parm.parm.capture.timeperframe.denominator =
        static_cast<uint32_t>(std::llround(config.rate_hz * 1000.0));
    if (ioctl(VIDIOC_S_PARM, &parm) == -1) {
      const int err = errno;
      noteLoss(err);
      return fail(failure("VIDIOC_S_PARM " + formatRateHz(config.rate_hz) + " Hz", err));
    }
    const double actual = rateOfInterval(parm.parm.capture.timeperframe);
    if (std::abs(actual - config.rate_hz) > 0.01 * config.rate_hz) {
      return fail(path_ + " (" + card_ + ") does not offer " + request + " at " +
                  formatRateHz(config.rate_hz) + " Hz (it chose " + formatRateHz(actual) +
                  " Hz); it offers:\n" + describeFormats());
    }
  }
  if (has_parm && ioctl(VIDIOC_G_PARM, &parm) == 0) {
    rate_hz_ = rateOfInterval(parm.parm.capture.timeperframe);
  }

  // Buffers.
  v4l2_requestbuffers buffers{};
  buffers.count = static_cast<uint32_t>(config.buffer_count);
  buffers.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffers.memory = V4L2_MEMORY_MMAP;
  if (ioctl(VIDIOC_REQBUFS, &buffers) == -1) {
    const int err = errno;
    noteLoss(err);
    return fail(failure("VIDIOC_REQBUFS", err));
  }
  if (buffers.count < 2) {
    buffers_.resize(buffers.count);  // so that stopStreaming() frees them
    return fail(path_ + ": the driver granted only " + std::to_string(buffers.count) +
                " buffer(s)");
  }
  buffers_.resize(buffers.count);
  for (uint32_t i = 0; i < buffers.count; ++i) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = i;
    if (ioctl(VIDIOC_QUERYBUF, &buffer) == -1) {
      const int err = errno;
      noteLoss(err);
      return fail(failure("VIDIOC_QUERYBUF", err));
    }
    void* start =
        v4l2_mmap(nullptr, buffer.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, buffer.m.offset);
    if (start == MAP_FAILED) return fail(failure("mmap of buffer " + std::to_string(i), errno));
    buffers_[i] = Buffer{start, buffer.length};
  }
  for (uint32_t i = 0; i < buffers.count; ++i) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = i;
    if (ioctl(VIDIOC_QBUF, &buffer) == -1) {
      const int err = errno;
      noteLoss(err);
      return fail(failure("VIDIOC_QBUF", err));
    }
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (ioctl(VIDIOC_STREAMON, &type) == -1) {
    const int err = errno;
    noteLoss(err);
    return fail(failure("VIDIOC_STREAMON", err));
  }
  streaming_ = true;
  config_ = config;
  return true;
}

V4l2Status V4l2Device::dequeue(int timeout_ms, V4l2Frame* frame, std::string* error) {
  auto result = [&](V4l2Status status, const std::string& message) {
    if (error) *error = message;
    return status;
  };
  if (lost_) return result(V4l2Status::kDeviceLost, path_ + ": device lost");
  if (!streaming_) return result(V4l2Status::kError, path_ + ": not streaming");
  if (held_ && !requeue(error)) {
    return lost_ ? V4l2Status::kDeviceLost : V4l2Status::kError;
  }
  pollfd pfd{fd_, POLLIN, 0};
  const int ready = ::poll(&pfd, 1, std::max(timeout_ms, 0));
  if (ready == 0) {
    return result(V4l2Status::kTimeout,
                  path_ + ": no frame within " + std::to_string(timeout_ms) + " ms");
  }
  if (ready < 0) {
    const int err = errno;
    if (err == EINTR) return result(V4l2Status::kTimeout, path_ + ": wait interrupted");
    return result(V4l2Status::kError, failure("poll", err));
  }
  if ((pfd.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0 && (pfd.revents & POLLIN) == 0) {
    lost_ = true;
    return result(V4l2Status::kDeviceLost, path_ + ": device lost (poll reports an error)");
  }
  v4l2_buffer buffer{};
  buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer.memory = V4L2_MEMORY_MMAP;
  if (ioctl(VIDIOC_DQBUF, &buffer) == -1) {
    const int err = errno;
    if (err == EAGAIN) return result(V4l2Status::kTimeout, path_ + ": no frame ready");
    if (noteLoss(err)) return result(V4l2Status::kDeviceLost, failure("VIDIOC_DQBUF", err));
    return result(V4l2Status::kError, failure("VIDIOC_DQBUF", err));
  }
  if (buffer.index >= buffers_.size()) {
    return result(V4l2Status::kError, path_ + ": the driver returned buffer " +
                                          std::to_string(buffer.index) + " of " +
                                          std::to_string(buffers_.size()));
  }
  held_ = buffer.index;
  const Buffer& mapped = buffers_[buffer.index];
  V4l2Frame out;
  out.image.format = config_.format;
  out.image.width = config_.width;
  out.image.height = config_.height;
  out.image.stride = stride_;
  out.image.data = static_cast<const uint8_t*>(mapped.start);
  out.image.bytes = std::min<size_t>(buffer.bytesused, mapped.length);
  out.timestamp_ns = timevalToNs(buffer.timestamp);
  out.timestamp_monotonic =
      (buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
  out.sequence = buffer.sequence;
  out.flags = buffer.flags;
  out.corrupt = (buffer.flags & V4L2_BUF_FLAG_ERROR) != 0;
  out.buffer_index = buffer.index;
  *frame = out;
  return V4l2Status::kOk;
}

bool V4l2Device::requeue(std::string* error) {
  if (!held_) return true;
  v4l2_buffer buffer{};
  buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer.memory = V4L2_MEMORY_MMAP;
  buffer.index = *held_;
  held_.reset();
  if (ioctl(VIDIOC_QBUF, &buffer) == -1) {
    const int err = errno;
    noteLoss(err);
    if (error) *error = failure("VIDIOC_QBUF", err);
    return false;
  }
  return true;
}

std::optional<V4l2ControlRange> V4l2Device::queryControl(std::string_view name,
                                                         std::string* error) const {
  auto fail = [&](const std::string& message) -> std::optional<V4l2ControlRange> {
    if (error) *error = message;
    return std::nullopt;
  };
  const std::optional<uint32_t> id = controlIdFromName(name);
  if (!id) {
    return fail(path_ + ": unknown control '" + std::string(name) +
                "' (known: " + knownControlNames() + ")");
  }
  v4l2_queryctrl query{};
  query.id = *id;
  if (ioctl(VIDIOC_QUERYCTRL, &query) == -1) {
    const int err = errno;
    if (err == EINVAL) {
      return fail(path_ + " (" + card_ + ") does not support control " + std::string(name));
    }
    return fail(failure("VIDIOC_QUERYCTRL " + std::string(name), err));
  }
  if ((query.flags & V4L2_CTRL_FLAG_DISABLED) != 0) {
    return fail(path_ + " (" + card_ + ") does not support control " + std::string(name) +
                " (disabled)");
  }
  if ((query.flags & V4L2_CTRL_FLAG_READ_ONLY) != 0) {
    return fail(path_ + ": control " + std::string(name) + " is read-only");
  }
  return V4l2ControlRange{query.minimum, query.maximum, query.step, query.default_value};
}

bool V4l2Device::setControl(std::string_view name, int64_t value, std::string* error) {
  const std::optional<V4l2ControlRange> range = queryControl(name, error);
  if (!range) return false;
  if (std::string problem = checkControlValue(name, value, *range); !problem.empty()) {
    if (error) *error = path_ + ": " + problem;
    return false;
  }
  v4l2_control control{};
  control.id = *controlIdFromName(name);
  control.value = static_cast<int32_t>(value);
  if (ioctl(VIDIOC_S_CTRL, &control) == -1) {
    const int err = errno;
    noteLoss(err);
    std::string message =
        failure("VIDIOC_S_CTRL " + std::string(name) + "=" + std::to_string(value), err);
    if (err == EACCES && name == "exposure_absolute") {
      message += " (set exposure_auto to 1, manual, first)";
    }
    if (error) *error = message;
    return false;
  }
  return true;
}

}  // namespace cblox
