#include "drivers/libcamera/libcamera_camera.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <optional>
#include <span>
#include <sstream>
#include <utility>

#include <libcamera/control_ids.h>

#include "drivers/libcamera/camera_manager_handle.h"
#include "drivers/libcamera/frame_planes.h"
#include "drivers/libcamera/libcamera_format.h"

namespace cblox {
namespace {

namespace controls = libcamera::controls;

bool setError(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return false;
}

std::string errnoText(int negative_errno) { return std::strerror(-negative_errno); }

std::string sizeText(const libcamera::Size& size) {
  return std::to_string(size.width) + "x" + std::to_string(size.height);
}

// "YUYV (libcamera YUYV): 640x480 1280x720; MJPEG (libcamera MJPEG): ..." for messages.
std::string describeOffers(const libcamera::StreamFormats& offers) {
  std::string text;
  for (const libcamera::PixelFormat& format : offers.pixelformats()) {
    if (!text.empty()) text += "; ";
    text += describeLibcameraFormat(format) + ":";
    const std::vector<libcamera::Size> sizes = offers.sizes(format);
    if (sizes.empty()) {
      text += ' ';
      text += offers.range(format).toString();
    } else {
      for (const libcamera::Size& size : sizes) {
        text += ' ';
        text += sizeText(size);
      }
    }
  }
  return text.empty() ? "nothing" : text;
}

// Integer or float bounds of a control, when the camera gives them.
template <typename T>
std::optional<std::pair<T, T>> bounds(const libcamera::ControlInfo& info) {
  constexpr libcamera::ControlType type = libcamera::details::control_type<T>::value;
  if (info.min().type() != type || info.max().type() != type) return std::nullopt;
  return std::pair<T, T>(info.min().get<T>(), info.max().get<T>());
}

template <typename T>
std::string rangeText(const std::pair<T, T>& range) {
  std::ostringstream text;
  text << "[" << range.first << ", " << range.second << "]";
  return text.str();
}

}  // namespace

std::string LibcameraStreamFormat::describe() const {
  return describeLibcameraFormat(libcamera_format) + " " + std::to_string(width) + "x" +
         std::to_string(height) + " stride " + std::to_string(stride) + ", " +
         std::to_string(buffer_count) + " buffers";
}

std::unique_ptr<LibcameraCamera> LibcameraCamera::open(const LibcameraCameraConfig& config,
                                                       std::string* error) {
  if (const std::string invalid = config.validate(); !invalid.empty()) {
    setError(error, "libcamera config: " + invalid);
    return nullptr;
  }
  // From here on, the destructor undoes whatever was done when a step fails.
  std::unique_ptr<LibcameraCamera> camera(new LibcameraCamera());
  camera->manager_ = sharedCameraManager(error);
  if (camera->manager_ == nullptr) return nullptr;
  camera->camera_ = findLibcameraCamera(*camera->manager_, config.camera_id, error);
  if (camera->camera_ == nullptr) return nullptr;
  camera->id_ = camera->camera_->id();
  if (const int result = camera->camera_->acquire(); result < 0) {
    setError(error, "libcamera camera '" + camera->id_ + "' " +
                        (result == -EBUSY ? "is busy (in use by another program or source)"
                                          : "cannot be acquired: " + errnoText(result)));
    return nullptr;
  }
  camera->acquired_ = true;
  if (!camera->configureStream(config, error) || !camera->setUpControls(config, error) ||
      !camera->allocateBuffers(error)) {
    return nullptr;
  }
  camera->camera_->requestCompleted.connect(camera.get(), &LibcameraCamera::onRequestCompleted);
  camera->camera_->disconnected.connect(camera.get(), &LibcameraCamera::onDisconnected);
  camera->signals_connected_ = true;
  return camera;
}

bool LibcameraCamera::configureStream(const LibcameraCameraConfig& config, std::string* error) {
  const std::string name = "libcamera camera '" + id_ + "'";
  for (const libcamera::StreamRole role :
       {libcamera::StreamRole::VideoRecording, libcamera::StreamRole::Viewfinder}) {
    configuration_ = camera_->generateConfiguration({role});
    if (configuration_ != nullptr && !configuration_->empty()) break;
  }
  if (configuration_ == nullptr || configuration_->empty()) {
    return setError(error, name + " has no video stream configuration");
  }
  const libcamera::PixelFormat asked_format =
      *parseLibcameraPixelFormat(config.pixel_format, nullptr);
  const libcamera::Size asked_size(static_cast<unsigned int>(config.width),
                                   static_cast<unsigned int>(config.height));
  libcamera::StreamConfiguration& stream = configuration_->at(0);
  const libcamera::StreamFormats offers = stream.formats();
  stream.pixelFormat = asked_format;
  stream.size = asked_size;
  stream.bufferCount = config.buffer_count;
  const std::string asked = describeLibcameraFormat(asked_format) + " " + sizeText(asked_size);

  const libcamera::CameraConfiguration::Status status = configuration_->validate();
  if (status == libcamera::CameraConfiguration::Invalid) {
    return setError(error, name + " rejects " + asked + "; it offers " + describeOffers(offers));
  }
  if (stream.pixelFormat != asked_format || stream.size != asked_size) {
    return setError(error, name + " cannot deliver " + asked + " (libcamera proposed " +
                               describeLibcameraFormat(stream.pixelFormat) + " " +
                               sizeText(stream.size) + "); it offers " + describeOffers(offers));
  }
  if (stream.bufferCount != config.buffer_count) {
    warnings_.push_back(name + ": buffer_count " + std::to_string(config.buffer_count) +
                        " changed to " + std::to_string(stream.bufferCount) + " by the camera");
  }
  if (const int result = camera_->configure(configuration_.get()); result < 0) {
    return setError(error, name + ": cannot configure " + asked + ": " + errnoText(result));
  }
  stream_ = stream.stream();
  format_.libcamera_format = stream.pixelFormat;
  format_.format = *pixelFormatFromLibcamera(stream.pixelFormat);
  format_.width = static_cast<int>(stream.size.width);
  format_.height = static_cast<int>(stream.size.height);
  format_.stride = stream.stride;
  return true;
}

bool LibcameraCamera::setUpControls(const LibcameraCameraConfig& config, std::string* error) {
  const std::string name = "libcamera camera '" + id_ + "'";
  const libcamera::ControlInfoMap& available = camera_->controls();
  controls_ = libcamera::ControlList(controls::controls);
  const auto has = [&available](const libcamera::ControlId& id) {
    return available.count(&id) > 0;
  };
  if (config.rate_hz > 0.0) {
    if (has(controls::FrameDurationLimits)) {
      const int64_t frame_us = std::llround(1e6 / config.rate_hz);
      controls_.set(controls::FrameDurationLimits, {frame_us, frame_us});
    } else {
      warnings_.push_back(name +
                          " has no FrameDurationLimits control: it runs at its own rate, "
                          "not the " +
                          std::to_string(config.rate_hz) + " Hz asked");
    }
  }
  const bool manual = config.exposure_us.has_value() || config.analogue_gain.has_value();
  if (config.exposure_us) {
    if (has(controls::ExposureTime)) {
      const auto range = bounds<int32_t>(available.at(&controls::ExposureTime));
      if (range && (*config.exposure_us < range->first || *config.exposure_us > range->second)) {
        return setError(error, name + ": exposure_us " + std::to_string(*config.exposure_us) +
                                   " is outside the camera's range " + rangeText(*range));
      }
      controls_.set(controls::ExposureTime, static_cast<int32_t>(*config.exposure_us));
    } else {
      warnings_.push_back(name + " has no ExposureTime control: exposure_us ignored");
    }
  }
  if (config.analogue_gain) {
    if (has(controls::AnalogueGain)) {
      const auto range = bounds<float>(available.at(&controls::AnalogueGain));
      const float gain = static_cast<float>(*config.analogue_gain);
      if (range && (gain < range->first || gain > range->second)) {
        return setError(error, name + ": analogue_gain " + std::to_string(*config.analogue_gain) +
                                   " is outside the camera's range " + rangeText(*range));
      }
      controls_.set(controls::AnalogueGain, gain);
    } else {
      warnings_.push_back(name + " has no AnalogueGain control: analogue_gain ignored");
    }
  }
  if (manual && has(controls::AeEnable)) controls_.set(controls::AeEnable, false);
  return true;
}

bool LibcameraCamera::allocateBuffers(std::string* error) {
  const std::string name = "libcamera camera '" + id_ + "'";
  allocator_ = std::make_unique<libcamera::FrameBufferAllocator>(camera_);
  if (const int result = allocator_->allocate(stream_); result < 0) {
    return setError(error, name + ": cannot allocate frame buffers: " + errnoText(result));
  }
  const std::vector<std::unique_ptr<libcamera::FrameBuffer>>& buffers =
      allocator_->buffers(stream_);
  if (buffers.empty()) return setError(error, name + ": no frame buffers were allocated");
  for (size_t i = 0; i < buffers.size(); ++i) {
    std::string map_error;
    std::optional<MappedFrameBuffer> mapped = MappedFrameBuffer::map(*buffers[i], &map_error);
    if (!mapped) return setError(error, name + ": buffer " + std::to_string(i) + ": " + map_error);
    mappings_.push_back(std::move(*mapped));
    std::unique_ptr<libcamera::Request> request = camera_->createRequest(i);
    if (request == nullptr) return setError(error, name + ": cannot create a request");
    if (const int result = request->addBuffer(stream_, buffers[i].get()); result < 0) {
      return setError(error, name + ": cannot add buffer " + std::to_string(i) +
                                 " to its request: " + errnoText(result));
    }
    requests_.push_back(std::move(request));
  }
  format_.buffer_count = static_cast<unsigned int>(buffers.size());
  return true;
}

LibcameraCamera::~LibcameraCamera() {
  stop();
  if (signals_connected_) {
    camera_->requestCompleted.disconnect(this);
    camera_->disconnected.disconnect(this);
  }
  requests_.clear();  // before the buffers they point to
  mappings_.clear();
  if (allocator_ != nullptr && stream_ != nullptr) allocator_->free(stream_);
  allocator_.reset();
  configuration_.reset();
  if (acquired_) camera_->release();
  camera_.reset();
  manager_.reset();  // the last holder stops the manager
}

bool LibcameraCamera::start(std::string* error) {
  if (running_) return true;
  const std::string name = "libcamera camera '" + id_ + "'";
  completed_.clear();
  if (const int result = camera_->start(&controls_); result < 0) {
    return setError(error, name + ": cannot start: " + errnoText(result));
  }
  running_ = true;
  for (const std::unique_ptr<libcamera::Request>& request : requests_) {
    request->reuse(libcamera::Request::ReuseBuffers);
    request->controls().merge(controls_);
    if (const int result = camera_->queueRequest(request.get()); result < 0) {
      stop();
      return setError(error, name + ": cannot queue a request: " + errnoText(result));
    }
  }
  return true;
}

void LibcameraCamera::stop() {
  if (!running_) return;
  camera_->stop();  // completes every pending request as cancelled, on this thread
  completed_.clear();
  running_ = false;
}

LibcameraCamera::WaitResult LibcameraCamera::waitFrame(
    std::chrono::nanoseconds timeout, const std::function<void(const LibcameraFrame&)>& consume) {
  WaitResult result;
  if (!running_) {
    result.status = WaitStatus::kError;
    result.message = "libcamera camera '" + id_ + "' is not running";
    return result;
  }
  libcamera::Request* request = nullptr;
  switch (completed_.pop(timeout, &request)) {
    case CompletedRequestQueue::PopResult::kTimeout:
      result.status = WaitStatus::kTimeout;
      return result;
    case CompletedRequestQueue::PopResult::kClosed:
      result.status = WaitStatus::kDisconnected;
      result.message = "libcamera camera '" + id_ + "' was disconnected";
      return result;
    case CompletedRequestQueue::PopResult::kRequest:
      break;
  }
  const auto requeue = [this, request, &result] {
    request->reuse(libcamera::Request::ReuseBuffers);
    if (const int code = camera_->queueRequest(request); code < 0) {
      result.status = WaitStatus::kError;
      result.message =
          "libcamera camera '" + id_ + "': cannot queue a request again: " + errnoText(code);
    }
  };
  const libcamera::FrameBuffer* buffer = request->findBuffer(stream_);
  const auto drop = [&result](const char* kind) {
    result.status = WaitStatus::kDropped;
    result.drop_kind = kind;
  };
  if (request->status() == libcamera::Request::RequestCancelled) {
    drop("request_cancelled");
  } else if (buffer == nullptr || request->cookie() >= mappings_.size()) {
    drop("no_buffer");
  } else if (buffer->metadata().status == libcamera::FrameMetadata::FrameError) {
    drop("frame_error");
  } else if (buffer->metadata().status == libcamera::FrameMetadata::FrameCancelled) {
    drop("frame_cancelled");
  } else {
    const libcamera::FrameMetadata& metadata = buffer->metadata();
    const MappedFrameBuffer& mapped = mappings_[request->cookie()];
    std::vector<FramePlane> planes(mapped.planeCount());
    const auto used = metadata.planes();
    for (size_t k = 0; k < planes.size(); ++k) {
      planes[k].mapped = mapped.plane(k);
      planes[k].bytes_used = k < used.size() ? used[k].bytesused : 0;
    }
    LibcameraFrame frame;
    frame.image = assembleRawImage(format_.format, format_.width, format_.height, format_.stride,
                                   planes, &scratch_);
    frame.sequence = metadata.sequence;
    const std::optional<int64_t> sensor_ns = request->metadata().get(controls::SensorTimestamp);
    frame.sensor_timestamp = sensor_ns.has_value();
    frame.monotonic_ns = sensor_ns.value_or(static_cast<int64_t>(metadata.timestamp));
    result.status = WaitStatus::kFrame;
    try {
      consume(frame);
    } catch (...) {
      requeue();
      throw;
    }
  }
  requeue();
  return result;
}

void LibcameraCamera::onRequestCompleted(libcamera::Request* request) { completed_.push(request); }

void LibcameraCamera::onDisconnected() { completed_.close(); }

}  // namespace cblox
