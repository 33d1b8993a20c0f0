#include "drivers/v4l2/v4l2_source.h"

#include <poll.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "drivers/pixel/pixel_convert.h"
#include "drivers/v4l2/v4l2_frame_decoder.h"

namespace cblox {
namespace {

constexpr int64_t kMaxReopenWaitNs = 1'000'000'000;  // next() blocks at most this long

std::string joinDevices(const std::vector<std::string>& devices) {
  std::string text;
  for (const std::string& device : devices) {
    if (!text.empty()) text += '+';
    text += device;
  }
  return text;
}

StereoPairerOptions pairerOptions(const V4l2SourceConfig& config) {
  StereoPairerOptions options;
  options.tolerance_ns = std::max<int64_t>(std::llround(config.pair_tolerance_ms * 1e6), 1);
  options.max_wait_ns = std::max<int64_t>(options.tolerance_ns, 200'000'000);
  options.max_queue = static_cast<size_t>(std::max(config.buffer_count, 2)) * 2;
  return options;
}

int64_t realtimeNowNs() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

int remainingMs(int64_t deadline_ns, int64_t now_ns) {
  if (deadline_ns <= now_ns) return 0;
  return static_cast<int>(
      std::min<int64_t>((deadline_ns - now_ns + 999'999) / 1'000'000, 1'000'000));
}

}  // namespace

V4l2Source::V4l2Source(V4l2SourceConfig config, std::shared_ptr<const StereoRectifier> rectifier)
    : config_(std::move(config)),
      format_(pixelFormatFromName(config_.pixel_format).value_or(PixelFormat::kYuyv)),
      rectifier_(std::move(rectifier)),
      pairer_(pairerOptions(config_)),
      drops_("v4l2:" + joinDevices(config_.devices)),
      schedule_(config_.reopen_min_s, config_.reopen_max_s) {}

V4l2Source::~V4l2Source() = default;

std::unique_ptr<V4l2Source> V4l2Source::open(const V4l2SourceConfig& config,
                                             std::shared_ptr<const StereoRectifier> rectifier,
                                             std::string* error) {
  auto fail = [&](const std::string& message) {
    if (error) *error = message;
    return nullptr;
  };
  if (std::string problem = config.validate(); !problem.empty()) {
    return fail("v4l2 source: " + problem);
  }
  const bool stereo = config.mode == V4l2Mode::kStereoPair || config.mode == V4l2Mode::kSideBySide;
  const int camera_width = config.cameraWidth();  // Y8I side by side: full-width views
  if (stereo && rectifier) {
    const PinholeIntrinsics& raw = rectifier->raw().left.intrinsics;
    if (raw.width != camera_width || raw.height != config.height) {
      return fail("v4l2 source: the stereo calibration " + rectifier->raw().source + " is for " +
                  std::to_string(raw.width) + "x" + std::to_string(raw.height) +
                  " images, the cameras deliver " + std::to_string(camera_width) + "x" +
                  std::to_string(config.height));
    }
  }
  std::unique_ptr<V4l2Source> source(new V4l2Source(config, stereo ? rectifier : nullptr));
  std::string why;
  if (!source->openDevices(&why)) return fail(why);

  SourceInfo& info = source->info_;
  info.name = "v4l2:" + joinDevices(config.devices);
  info.live = true;
  const double device_rate = source->devices_.front()->rateHz();
  info.rate_hz = device_rate > 0.0 ? device_rate : config.rate_hz;
  for (const auto& device : source->devices_) {
    info.notes.push_back(device->path() + ": " + device->card() + " (" + device->driver() + ", " +
                         device->busInfo() + "), " + config.pixel_format + " " +
                         std::to_string(config.width) + "x" + std::to_string(config.height) +
                         " at " + formatRateHz(device->rateHz()) + " Hz, " +
                         std::to_string(device->bufferCount()) + " buffers");
  }
  if (config.mode == V4l2Mode::kSideBySide) {
    info.notes.push_back(
        std::string(source->format_ == PixelFormat::kY8i ? "interleaved" : "side by side") +
        " stereo: two " + std::to_string(camera_width) + "x" + std::to_string(config.height) +
        " views in each frame");
  }
  if (stereo) {
    if (source->rectifier_) {
      info.stereo = source->rectifier_->rectified();
    } else {
      info.notes.push_back("no stereo calibration: frames carry the raw, unrectified pair");
    }
  }
  if (config.mode == V4l2Mode::kDepth) {
    info.depth_intrinsics = config.depth_intrinsics;
    info.T_C_D = config.T_B_D;  // no stereo in this source: C is the rig's body frame
    info.depth_min_m = config.depth_min_m;
    info.depth_max_m = config.depth_max_m;
    if (!config.depth_intrinsics) {
      info.notes.push_back("no depth intrinsics given: depth frames cannot be integrated");
    }
  }
  return source;
}

bool V4l2Source::openDevices(std::string* error) {
  closeDevices();
  std::vector<std::unique_ptr<V4l2Device>> devices;
  for (const std::string& path : config_.devices) {
    std::unique_ptr<V4l2Device> device = V4l2Device::open(path, error);
    if (!device) return false;
    if (config_.exposure) {
      if (!device->setControl("exposure_auto", 1, error) ||  // V4L2_EXPOSURE_MANUAL
          !device->setControl("exposure_absolute", *config_.exposure, error)) {
        return false;
      }
    }
    if (config_.gain && !device->setControl("gain", *config_.gain, error)) return false;
    V4l2StreamConfig stream;
    stream.format = format_;
    stream.width = config_.width;
    stream.height = config_.height;
    stream.rate_hz = config_.rate_hz;
    stream.buffer_count = config_.buffer_count;
    if (!device->configure(stream, error)) return false;
    devices.push_back(std::move(device));
  }
  devices_ = std::move(devices);
  sequence_offset_.reset();
  last_sequence_.reset();
  consecutive_stalls_ = 0;
  return true;
}

void V4l2Source::closeDevices() {
  devices_.clear();
  std::vector<StereoDrop> flushed;
  pairer_.clear(&flushed);
  pending_[0].clear();
  pending_[1].clear();
  ready_.clear();
}

void V4l2Source::drop(std::string_view kind, const std::string& message) {
  std::lock_guard<std::mutex> lock(mutex_);
  drops_.count(kind, message);
}

FrameSource::Status V4l2Source::deviceLost(const std::string& why, std::string* error) {
  closeDevices();
  std::lock_guard<std::mutex> lock(mutex_);
  ++counters_.device_lost;
  schedule_.lost(steadyNowNs());
  last_loss_ = why;
  if (error) *error = why + "; " + schedule_.status(joinDevices(config_.devices), steadyNowNs());
  return Status::kError;
}

FrameSource::Status V4l2Source::stall(std::string* error) {
  ++consecutive_stalls_;
  const std::string message = "no frame from " + joinDevices(config_.devices) + " for " +
                              formatSeconds(config_.frame_timeout_s) + " s (stall " +
                              std::to_string(consecutive_stalls_) + "/" +
                              std::to_string(config_.stalls_before_reopen) + ")";
  drop("stall", message);
  if (consecutive_stalls_ >= config_.stalls_before_reopen) {
    return deviceLost(message + ": giving the device up", error);
  }
  if (error) *error = message;
  return Status::kError;
}

FrameSource::Status V4l2Source::reopen(std::string* error) {
  const std::string devices = joinDevices(config_.devices);
  int64_t now = steadyNowNs();
  int64_t due_ns = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    due_ns = schedule_.nextAttemptNs();
  }
  if (now < due_ns) {
    std::this_thread::sleep_for(std::chrono::nanoseconds(std::min(due_ns - now, kMaxReopenWaitNs)));
    now = steadyNowNs();
  }
  if (now < due_ns) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (error) *error = schedule_.status(devices, now) + ": " + last_loss_;
    return Status::kError;
  }
  std::string why;
  const bool reopened = openDevices(&why);
  std::lock_guard<std::mutex> lock(mutex_);
  ++counters_.reopen_attempts;
  if (!reopened) {
    schedule_.failed(steadyNowNs());
    if (error) *error = "reopen failed: " + why + "; " + schedule_.status(devices, steadyNowNs());
    return Status::kError;
  }
  DropCounter::writeToStderr("v4l2:" + devices + ": reopened (attempt " +
                             std::to_string(schedule_.attempt()) + ")");
  schedule_.succeeded();
  last_loss_.clear();
  return Status::kFrame;  // the caller goes on to capture
}

FrameSource::Status V4l2Source::next(CaptureFrame* frame, std::string* error) {
  bool reopening = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    reopening = schedule_.reopening();
  }
  if (reopening) {
    if (Status status = reopen(error); status != Status::kFrame) return status;
  }
  return config_.mode == V4l2Mode::kStereoPair ? nextPair(frame, error) : nextSingle(frame, error);
}

int64_t V4l2Source::frameTimestampNs(const V4l2Frame& frame) {
  return frame.timestamp_monotonic ? clock_.toRealtimeNs(frame.timestamp_ns) : realtimeNowNs();
}

int64_t V4l2Source::frameId(uint32_t sequence) {
  if (!sequence_offset_ || (last_sequence_ && sequence <= *last_sequence_)) {
    sequence_offset_ = last_frame_id_ + 1 - static_cast<int64_t>(sequence);
  }
  last_sequence_ = sequence;
  last_frame_id_ = static_cast<int64_t>(sequence) + *sequence_offset_;
  return last_frame_id_;
}

bool V4l2Source::fillStereo(GrayImage left, GrayImage right, CaptureFrame* frame,
                            std::string* why) const {
  if (!rectifier_) {
    frame->left = std::move(left);
    frame->right = std::move(right);
    return true;
  }
  try {
    rectifier_->rectify(left, right, &frame->left, &frame->right);
  } catch (const std::exception& e) {
    *why = e.what();
    return false;
  }
  return true;
}

FrameSource::Status V4l2Source::nextSingle(CaptureFrame* frame, std::string* error) {
  V4l2Device& device = *devices_.front();
  const int64_t deadline = steadyNowNs() + std::llround(config_.frame_timeout_s * 1e9);
  while (true) {
    const int timeout_ms = remainingMs(deadline, steadyNowNs());
    if (timeout_ms <= 0) return stall(error);
    V4l2Frame raw;
    std::string message;
    const V4l2Status status = device.dequeue(timeout_ms, &raw, &message);
    if (status == V4l2Status::kTimeout) continue;
    if (status != V4l2Status::kOk) return deviceLost(message, error);
    if (raw.corrupt) {
      drop("corrupt", device.path() + ": frame " + std::to_string(raw.sequence) +
                          " flagged V4L2_BUF_FLAG_ERROR by the driver");
      if (!device.requeue(&message)) return deviceLost(message, error);
      continue;
    }
    V4l2Images images;
    const ConvertResult converted =
        decodeV4l2Frame(config_.mode, raw.image, config_.color, config_.depth_scale_m, &images);
    const int64_t timestamp_ns = frameTimestampNs(raw);
    const uint32_t sequence = raw.sequence;
    if (!device.requeue(&message)) return deviceLost(message, error);
    if (!converted) {
      drop(convertErrorName(converted.error), device.path() + ": " + converted.message);
      continue;
    }
    CaptureFrame out;
    out.timestamp_ns = timestamp_ns;
    if (config_.mode == V4l2Mode::kSideBySide) {
      std::string why;
      if (!fillStereo(std::move(images.left), std::move(images.right), &out, &why)) {
        drop("rectify_failed", why);
        continue;
      }
    } else {
      out.left = std::move(images.left);
      out.depth = std::move(images.depth);
      out.color = std::move(images.color);
    }
    out.frame_id = frameId(sequence);
    consecutive_stalls_ = 0;
    *frame = std::move(out);
    std::lock_guard<std::mutex> lock(mutex_);
    ++counters_.frames;
    return Status::kFrame;
  }
}

bool V4l2Source::readPairSide(int side, Status* status, std::string* error) {
  V4l2Device& device = *devices_[static_cast<size_t>(side)];
  V4l2Frame raw;
  std::string message;
  const V4l2Status result = device.dequeue(0, &raw, &message);
  if (result == V4l2Status::kTimeout) return true;
  if (result != V4l2Status::kOk) {
    *status = deviceLost(message, error);
    return false;
  }
  if (raw.corrupt) {
    drop("corrupt", device.path() + ": frame " + std::to_string(raw.sequence) +
                        " flagged V4L2_BUF_FLAG_ERROR by the driver");
    if (!device.requeue(&message)) {
      *status = deviceLost(message, error);
      return false;
    }
    return true;
  }
  V4l2Images images;
  const ConvertResult converted =
      decodeV4l2Frame(V4l2Mode::kStereoPair, raw.image, false, 0.0, &images);
  const int64_t timestamp_ns = frameTimestampNs(raw);
  const uint32_t sequence = raw.sequence;
  if (!device.requeue(&message)) {
    *status = deviceLost(message, error);
    return false;
  }
  if (!converted) {
    drop(convertErrorName(converted.error), device.path() + ": " + converted.message);
    return true;
  }
  const uint64_t id = next_pending_id_++;
  pending_[side].emplace(id, PendingImage{std::move(images.left), timestamp_ns, sequence});
  std::vector<StereoPair> pairs;
  std::vector<StereoDrop> dropped;
  pairer_.push(side == 0 ? StereoSide::kLeft : StereoSide::kRight, timestamp_ns, id, &pairs,
               &dropped);
  for (const StereoDrop& d : dropped) {
    const int s = d.side == StereoSide::kLeft ? 0 : 1;
    pending_[s].erase(d.id);
    if (d.reason == StereoDropReason::kFlushed) continue;
    const char* name = s == 0 ? "left" : "right";
    if (d.reason == StereoDropReason::kOutOfOrder) {
      drop("out_of_order", std::string(name) + " frame at " + std::to_string(d.timestamp_ns) +
                               " ns is not newer than one already paired or dropped");
    } else {
      drop(std::string(name) + "_unpaired",
           std::string(name) + " frame at " + std::to_string(d.timestamp_ns) +
               " ns has no partner within " + formatRateHz(config_.pair_tolerance_ms) + " ms (" +
               std::string(stereoDropReasonName(d.reason)) + ")");
    }
  }
  for (const StereoPair& pair : pairs) {
    auto left = pending_[0].extract(pair.left_id);
    auto right = pending_[1].extract(pair.right_id);
    if (!left || !right) continue;  // cannot happen: every waiting id has an image
    ready_.emplace_back(std::move(left.mapped()), std::move(right.mapped()));
  }
  std::lock_guard<std::mutex> lock(mutex_);
  counters_.pairing = pairer_.stats();
  return true;
}

FrameSource::Status V4l2Source::nextPair(CaptureFrame* frame, std::string* error) {
  const int64_t deadline = steadyNowNs() + std::llround(config_.frame_timeout_s * 1e9);
  while (true) {
    while (!ready_.empty()) {
      auto [left, right] = std::move(ready_.front());
      ready_.pop_front();
      CaptureFrame out;
      out.timestamp_ns = left.timestamp_ns;
      std::string why;
      if (!fillStereo(std::move(left.image), std::move(right.image), &out, &why)) {
        drop("rectify_failed", why);
        continue;
      }
      out.frame_id = frameId(left.sequence);
      consecutive_stalls_ = 0;
      *frame = std::move(out);
      std::lock_guard<std::mutex> lock(mutex_);
      ++counters_.frames;
      return Status::kFrame;
    }
    const int timeout_ms = remainingMs(deadline, steadyNowNs());
    if (timeout_ms <= 0) return stall(error);
    pollfd fds[2] = {{devices_[0]->fd(), POLLIN, 0}, {devices_[1]->fd(), POLLIN, 0}};
    const int ready = ::poll(fds, 2, timeout_ms);
    if (ready < 0 && errno != EINTR) {
      return deviceLost(
          "v4l2:" + joinDevices(config_.devices) + ": poll failed: " + std::strerror(errno), error);
    }
    for (int side = 0; side < 2 && ready > 0; ++side) {
      if (fds[side].revents == 0) continue;
      Status status = Status::kError;
      if (!readPairSide(side, &status, error)) return status;
    }
  }
}

V4l2Stats V4l2Source::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  V4l2Stats stats = counters_;
  stats.dropped = drops_.counts();
  return stats;
}

std::string V4l2Source::health() const {
  const std::string devices = joinDevices(config_.devices);
  std::lock_guard<std::mutex> lock(mutex_);
  if (schedule_.reopening()) {
    std::string text = schedule_.status(devices, steadyNowNs());
    if (!last_loss_.empty()) text += ": " + last_loss_;
    return text;
  }
  std::string text = "streaming " + devices + ": " + std::to_string(counters_.frames) +
                     " frames, dropped " + drops_.summary();
  if (config_.mode == V4l2Mode::kStereoPair) {
    text += ", pair dt " + formatRateHz(static_cast<double>(counters_.pairing.last_dt_ns) * 1e-6) +
            " ms (max " +
            formatRateHz(static_cast<double>(counters_.pairing.max_abs_dt_ns) * 1e-6) +
            " ms), drift " + std::to_string(counters_.pairing.drift);
  }
  if (counters_.device_lost > 0) {
    text += ", device lost " + std::to_string(counters_.device_lost) + "x";
  }
  return text;
}

}  // namespace cblox
