#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>

namespace cblox {

/// What the integrator can do with a waiting frame now.
enum class FrameReadiness {
  kReady,   ///< its pose is known: integrate it
  kWait,    ///< its pose may still come: keep it
  kReject,  ///< it can never be served (no pose within the allowed gap, lost, ...)
};

/// Counters of an InTray since construction.
struct InTrayCounters {
  uint64_t received = 0;  ///< frames pushed
  uint64_t taken = 0;     ///< frames handed to the integrator
  uint64_t dropped = 0;   ///< superseded by a newer frame, or pushed out when full
  uint64_t rejected = 0;  ///< judged kReject
};

/// A bounded in-tray of frames, never an unbounded queue. The receiving thread pushes frames
/// (the oldest is dropped when `capacity` are waiting). The integrator takes the newest frame
/// that is ready, and every older waiting frame is dropped (counted) because the newer one
/// supersedes it ("newest frame wins", takeNewestReady); the tracker may instead take them in
/// order and catch up after a stall (takeOldestReady). Frames that are not ready yet
/// (their pose has not arrived) wait; frames that can never be served are rejected.
///
/// Thread-safety: all member functions are thread-safe (one mutex and a condition variable);
/// `readiness` is called with the mutex held and must not call back into this object.
template <typename Frame>
class InTray {
 public:
  explicit InTray(size_t capacity) : capacity_(capacity < 1 ? 1 : capacity) {}

  /// Adds a frame and wakes a waiting taker.
  void push(Frame frame) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++counters_.received;
      ++work_signal_;
      frames_.push_back(std::move(frame));
      while (frames_.size() > capacity_) {
        frames_.pop_front();
        ++counters_.dropped;
      }
    }
    wake_.notify_all();
  }

  /// Wakes a waiting taker without a frame (e.g. a pose arrived, or shutdown).
  void notify() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++work_signal_;
    }
    wake_.notify_all();
  }

  /// Blocks until something was pushed or notify() was called since the last call, or the
  /// timeout expires.
  void waitForWork(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait_for(lock, timeout, [this] { return work_signal_ != seen_signal_; });
    seen_signal_ = work_signal_;
  }

  /// Scans from the newest frame back: frames judged kReject are removed (counted rejected);
  /// the first kReady frame is returned and every older frame is dropped (counted); kWait
  /// frames stay. Returns std::nullopt when no frame is ready.
  std::optional<Frame> takeNewestReady(
      const std::function<FrameReadiness(const Frame&)>& readiness) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (size_t i = frames_.size(); i-- > 0;) {
      const FrameReadiness r = readiness(frames_[i]);
      if (r == FrameReadiness::kReject) {
        frames_.erase(frames_.begin() + static_cast<std::ptrdiff_t>(i));
        ++counters_.rejected;
        continue;
      }
      if (r == FrameReadiness::kReady) {
        Frame frame = std::move(frames_[i]);
        counters_.dropped += i;  // every older frame is superseded
        frames_.erase(frames_.begin(), frames_.begin() + static_cast<std::ptrdiff_t>(i) + 1);
        ++counters_.taken;
        return frame;
      }
    }
    return std::nullopt;
  }

  /// In order: scans from the oldest frame: frames judged kReject are removed (counted
  /// rejected); the first other frame is returned if kReady, and nothing is returned if it is
  /// kWait (a later frame is not served before it). Nothing is dropped here: frames are
  /// dropped only when pushed out of a full tray. Returns std::nullopt when no frame is ready.
  std::optional<Frame> takeOldestReady(
      const std::function<FrameReadiness(const Frame&)>& readiness) {
    std::lock_guard<std::mutex> lock(mutex_);
    while (!frames_.empty()) {
      const FrameReadiness r = readiness(frames_.front());
      if (r == FrameReadiness::kReject) {
        frames_.pop_front();
        ++counters_.rejected;
        continue;
      }
      if (r == FrameReadiness::kWait) return std::nullopt;
      Frame frame = std::move(frames_.front());
      frames_.pop_front();
      ++counters_.taken;
      return frame;
    }
    return std::nullopt;
  }

  size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return frames_.size();
  }

  InTrayCounters counters() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return counters_;
  }

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Frame> frames_;
  InTrayCounters counters_;
  uint64_t work_signal_ = 0, seen_signal_ = 0;
};

}  // namespace cblox
