#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "drivers/frame_source.h"
#include "drivers/stereo_depth/stereo_depth.h"

namespace cblox {

/// What the worker has done so far. Plain value type.
struct StereoDepthWorkerStats {
  uint64_t computed = 0;    ///< depth images published
  uint64_t superseded = 0;  ///< pairs replaced by a newer one before their turn
  uint64_t rate_limited = 0;  ///< pairs passed over to keep under max_rate_hz
  uint64_t failed = 0;        ///< pairs the matcher refused (size other than calibrated)
  double last_ms = 0.0;     ///< time of the last computation
  double mean_ms = 0.0;     ///< mean over all computations
  double mean_valid = 0.0;  ///< mean share of pixels with a depth
};

/// cblox-capture's dense-stereo thread: turns rectified pairs into depth frames off the
/// capture loop, so that a slow matcher never delays the stereo stream the tracker follows.
/// One pending pair at a time, newest wins (an older pending pair is counted as superseded);
/// at most max_rate_hz depth frames per second of frame time (0 = no limit). `publish` is
/// called on the worker thread with a copy of the frame (ids, time stamp, ground truth) whose
/// `depth` is the estimate (depthIntrinsics() of the estimator) and whose images are empty.
/// Thread-safe: offer() and stats() from any thread.
class StereoDepthWorker {
 public:
  using Publish = std::function<void(const CaptureFrame& frame)>;

  StereoDepthWorker(std::unique_ptr<StereoDepthEstimator> estimator, double max_rate_hz,
                    Publish publish);
  /// Computes the pending pair (if any), then stops the thread.
  ~StereoDepthWorker();

  StereoDepthWorker(const StereoDepthWorker&) = delete;
  StereoDepthWorker& operator=(const StereoDepthWorker&) = delete;

  /// Hands over a pair (copied). Pairs closer than 1 / max_rate_hz in frame time to the last
  /// accepted one are passed over.
  void offer(const CaptureFrame& frame);

  /// Waits until no pair is pending or being computed (for sources played as fast as possible
  /// whose last frames must not be lost at the end). Thread-safe.
  void drain();

  StereoDepthWorkerStats stats() const;

 private:
  void run();

  std::unique_ptr<StereoDepthEstimator> estimator_;
  const double max_rate_hz_;
  const Publish publish_;
  mutable std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::optional<CaptureFrame> pending_;
  bool busy_ = false;
  bool stop_ = false;
  bool said_failure_ = false;  // worker thread only
  std::optional<int64_t> last_accepted_ns_;
  StereoDepthWorkerStats stats_;
  std::thread thread_;  // last: starts after the members it uses
};

}  // namespace cblox
