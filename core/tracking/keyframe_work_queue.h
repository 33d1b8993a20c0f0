#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>

namespace cblox {

class Keyframe;

/// The keyframes waiting for one worker thread (local mapping, loop closing), oldest first,
/// and whether the worker has one in hand. All methods are thread-safe.
class KeyframeWorkQueue {
 public:
  /// Appends a keyframe and wakes the worker.
  void push(Keyframe* keyframe) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      queue_.push_back(keyframe);
    }
    cv_.notify_all();
  }
  /// The oldest keyframe, now "in hand" until done(); nullptr when there is none.
  Keyframe* tryPop() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.empty()) return nullptr;
    Keyframe* keyframe = queue_.front();
    queue_.pop_front();
    busy_ = true;
    return keyframe;
  }
  /// The keyframe in hand is finished.
  void done() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
    }
    cv_.notify_all();
  }
  /// Blocks until a keyframe waits (true) or stop() was called (false).
  bool waitForWork() {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [this] { return stop_ || !queue_.empty(); });
    return !stop_;
  }
  /// Makes waitForWork() and waitUntilIdle() return.
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
  }
  /// Blocks until nothing waits and nothing is in hand (or stop()).
  void waitUntilIdle() {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [this] { return stop_ || (queue_.empty() && !busy_); });
  }
  size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return queue_.size();
  }
  /// Nothing waits and nothing is in hand.
  bool idle() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return queue_.empty() && !busy_;
  }
  /// More keyframes wait, or the worker is asked to stop (long work should be skipped).
  bool moreWorkOrStopping() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return stop_ || !queue_.empty();
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Keyframe*> queue_;
  bool busy_ = false;
  bool stop_ = false;
};

}  // namespace cblox
