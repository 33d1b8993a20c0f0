#include "drivers/libcamera/libcamera_source.h"

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <thread>
#include <utility>

#include "drivers/pixel/pixel_convert.h"

namespace cblox {

std::unique_ptr<LibcameraSource> LibcameraSource::open(const LibcameraSourceConfig& config,
                                                       std::string* error) {
  if (const std::string invalid = config.validate(); !invalid.empty()) {
    if (error != nullptr) *error = "libcamera source: " + invalid;
    return nullptr;
  }
  std::unique_ptr<LibcameraCamera> camera = LibcameraCamera::open(config.camera, error);
  if (camera == nullptr || !camera->start(error)) return nullptr;
  return std::unique_ptr<LibcameraSource>(new LibcameraSource(config, std::move(camera)));
}

LibcameraSource::LibcameraSource(const LibcameraSourceConfig& config,
                                 std::unique_ptr<LibcameraCamera> camera)
    : config_(config),
      name_("libcamera:" + camera->id()),
      camera_(std::move(camera)),
      restart_(config.restart_backoff_s, config.restart_backoff_max_s),
      drops_(name_) {
  info_.name = name_;
  info_.live = true;
  info_.rate_hz = config_.camera.rate_hz;
  if (config_.rectifier != nullptr) info_.stereo = config_.rectifier->rectified();
  format_text_ = camera_->format().describe();
  info_.notes.push_back("stream " + format_text_ + ", " +
                        std::string(libcameraStereoModeName(config_.mode)));
  for (const std::string& warning : camera_->warnings()) info_.notes.push_back(warning);
  if (config_.mode == LibcameraStereoMode::kSideBySide && config_.rectifier == nullptr) {
    info_.notes.push_back("no calibration: the side-by-side halves are delivered unrectified");
  }
  state_ = "streaming";
}

LibcameraSource::~LibcameraSource() = default;  // the camera stops and releases itself

std::map<std::string, int64_t, std::less<>> LibcameraSource::dropCounts() const {
  const std::lock_guard<std::mutex> lock(stats_mutex_);
  return drops_.counts();
}

void LibcameraSource::countDrop(std::string_view kind, const std::string& message) {
  const std::lock_guard<std::mutex> lock(stats_mutex_);
  drops_.count(kind, message);
}

std::string LibcameraSource::health() const {
  const std::lock_guard<std::mutex> lock(stats_mutex_);
  const std::string state = state_ == "streaming" ? name_ + " streaming" : state_;
  std::string text = state + " " + format_text_ + "; " + std::to_string(frames_) +
                     " frames; dropped " + drops_.summary() + "; " + std::to_string(restarts_) +
                     " restarts";
  if (!last_error_.empty()) text += " (last error: " + last_error_ + ")";
  return text;
}

FrameSource::Status LibcameraSource::fail(const std::string& kind, const std::string& message,
                                          std::string* error) {
  countDrop(kind, message);
  camera_.reset();  // stop, free, release
  const int64_t now = steadyNowNs();
  if (restart_.reopening()) {
    restart_.failed(now);  // a restart that delivered no frame: the next waits twice as long
  } else {
    restart_.lost(now);
  }
  const std::string status = restart_.status(name_, now);
  {
    const std::lock_guard<std::mutex> lock(stats_mutex_);
    state_ = status;
    last_error_ = message;
  }
  if (error != nullptr) *error = name_ + ": " + message + "; " + status;
  return Status::kError;
}

bool LibcameraSource::reopen(std::string* error) {
  std::this_thread::sleep_for(std::chrono::nanoseconds(
      std::max<int64_t>(0, restart_.nextAttemptNs() - steadyNowNs())));
  std::string open_error;
  std::unique_ptr<LibcameraCamera> camera = LibcameraCamera::open(config_.camera, &open_error);
  if (camera == nullptr || !camera->start(&open_error)) {
    if (error != nullptr) *error = open_error;
    return false;
  }
  camera_ = std::move(camera);
  const std::lock_guard<std::mutex> lock(stats_mutex_);
  ++restarts_;
  state_ = "streaming";
  format_text_ = camera_->format().describe();
  return true;
}

int64_t LibcameraSource::frameIdOf(uint32_t sequence) {
  const int64_t s = static_cast<int64_t>(sequence);
  if (!have_base_ || sequence_base_ + s < next_frame_id_) {
    // First frame, or the counter restarted (reopened camera) or wrapped: continue from here.
    sequence_base_ = next_frame_id_ - s;
    have_base_ = true;
  }
  const int64_t id = sequence_base_ + s;
  next_frame_id_ = id + 1;
  return id;
}

bool LibcameraSource::convert(const LibcameraFrame& raw, CaptureFrame* frame, std::string* kind,
                              std::string* message) {
  const auto failed = [kind, message](const ConvertResult& result) {
    *kind = "convert_" + std::string(convertErrorName(result.error));
    *message = result.message;
    return false;
  };
  if (config_.mode == LibcameraStereoMode::kMono) {
    if (ConvertResult result = toGray(raw.image, &frame->left); !result) return failed(result);
    frame->right = GrayImage();
    return true;
  }
  if (ConvertResult result = toGray(raw.image, &both_); !result) return failed(result);
  if (ConvertResult result = splitSideBySide(both_, &left_raw_, &right_raw_); !result) {
    return failed(result);
  }
  if (config_.rectifier == nullptr) {
    std::swap(frame->left, left_raw_);
    std::swap(frame->right, right_raw_);
    return true;
  }
  try {
    config_.rectifier->rectify(left_raw_, right_raw_, &frame->left, &frame->right);
  } catch (const std::invalid_argument& e) {
    *kind = "rectify";
    *message = e.what();
    return false;
  }
  return true;
}

FrameSource::Status LibcameraSource::next(CaptureFrame* frame, std::string* error) {
  const auto stall = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(config_.stall_timeout_s));
  if (camera_ == nullptr) {
    std::string open_error;
    if (!reopen(&open_error)) return fail("restart_failed", open_error, error);
  }
  const Clock::time_point since_good = Clock::now();
  Clock::time_point since_completed = since_good;
  while (true) {
    const Clock::time_point now = Clock::now();
    if (now - since_good >= stall) {
      // Requests complete, but none with a usable frame. The camera keeps running.
      const std::lock_guard<std::mutex> lock(stats_mutex_);
      const std::string message = name_ + ": no usable frame for " +
                                  formatSeconds(config_.stall_timeout_s) + " s" +
                                  " (dropped so far: " + drops_.summary() + ")";
      last_error_ = message;
      if (error != nullptr) *error = message;
      return Status::kError;
    }
    bool delivered = false;
    std::string kind, message;
    const LibcameraCamera::WaitResult result =
        camera_->waitFrame(since_completed + stall - now, [&](const LibcameraFrame& raw) {
          if (!convert(raw, frame, &kind, &message)) return;
          frame->frame_id = frameIdOf(raw.sequence);
          frame->timestamp_ns = clock_.toRealtimeNs(raw.monotonic_ns);
          delivered = true;
        });
    switch (result.status) {
      case LibcameraCamera::WaitStatus::kFrame:
        if (delivered) {
          frame->depth = DepthImage();
          frame->color = ColorImage();
          frame->T_G_C.reset();
          if (restart_.reopening()) restart_.succeeded();
          const std::lock_guard<std::mutex> lock(stats_mutex_);
          ++frames_;
          return Status::kFrame;
        }
        countDrop(kind, message);
        since_completed = Clock::now();
        break;
      case LibcameraCamera::WaitStatus::kDropped:
        countDrop(result.drop_kind, "libcamera completed a request without a frame");
        since_completed = Clock::now();
        break;
      case LibcameraCamera::WaitStatus::kTimeout:
        return fail(
            "stall",
            "no request completed for " + formatSeconds(config_.stall_timeout_s) + " s" + " (camera stalled)",
            error);
      case LibcameraCamera::WaitStatus::kDisconnected:
        return fail("disconnected", result.message, error);
      case LibcameraCamera::WaitStatus::kError:
        return fail("queue_error", result.message, error);
    }
  }
}

}  // namespace cblox
