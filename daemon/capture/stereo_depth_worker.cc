#include "daemon/capture/stereo_depth_worker.h"

#include <chrono>
#include <cstdio>
#include <exception>
#include <utility>

namespace cblox {

StereoDepthWorker::StereoDepthWorker(std::unique_ptr<StereoDepthEstimator> estimator,
                                     double max_rate_hz, Publish publish)
    : estimator_(std::move(estimator)),
      max_rate_hz_(max_rate_hz),
      publish_(std::move(publish)),
      thread_([this] { run(); }) {}

StereoDepthWorker::~StereoDepthWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void StereoDepthWorker::offer(const CaptureFrame& frame) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (max_rate_hz_ > 0 && last_accepted_ns_ &&
        static_cast<double>(frame.timestamp_ns - *last_accepted_ns_) * 1e-9 <
            1.0 / max_rate_hz_ &&
        frame.timestamp_ns >= *last_accepted_ns_) {
      ++stats_.rate_limited;
      return;
    }
    last_accepted_ns_ = frame.timestamp_ns;
    if (pending_) ++stats_.superseded;
    CaptureFrame copy;
    copy.frame_id = frame.frame_id;
    copy.timestamp_ns = frame.timestamp_ns;
    copy.left = frame.left;
    copy.right = frame.right;
    copy.T_G_C = frame.T_G_C;
    pending_ = std::move(copy);
  }
  wake_.notify_one();
}

void StereoDepthWorker::drain() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [&] { return !pending_ && !busy_; });
}

StereoDepthWorkerStats StereoDepthWorker::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void StereoDepthWorker::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_.wait(lock, [&] { return stop_ || pending_; });
    if (!pending_) break;  // stopping with nothing left
    CaptureFrame frame = std::move(*pending_);
    pending_.reset();
    busy_ = true;
    lock.unlock();
    const auto start = std::chrono::steady_clock::now();
    bool ok = true;
    StereoDepthStats depth_stats;
    try {
      depth_stats = estimator_->compute(frame.left, frame.right, &frame.depth);
    } catch (const std::exception& e) {  // a pair of another size: dropped, logged once
      if (!said_failure_) {
        std::fprintf(stderr, "cblox-capture: stereo depth of frame %lld skipped: %s\n",
                     static_cast<long long>(frame.frame_id), e.what());
        said_failure_ = true;
      }
      ok = false;
    }
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count();
    if (ok) {
      frame.left = GrayImage();
      frame.right = GrayImage();
      publish_(frame);
    }
    lock.lock();
    if (!ok) ++stats_.failed;
    if (ok) {
      StereoDepthWorkerStats& s = stats_;
      ++s.computed;
      s.last_ms = ms;
      s.mean_ms += (ms - s.mean_ms) / static_cast<double>(s.computed);
      const double valid = depth_stats.total_pixels > 0
                               ? static_cast<double>(depth_stats.valid_pixels) /
                                     depth_stats.total_pixels
                               : 0.0;
      s.mean_valid += (valid - s.mean_valid) / static_cast<double>(s.computed);
    }
    busy_ = false;
    if (!pending_) idle_.notify_all();
  }
  busy_ = false;
  idle_.notify_all();
}

}  // namespace cblox
