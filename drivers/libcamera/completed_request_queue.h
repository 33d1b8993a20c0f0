#pragma once

// Hand-over of completed libcamera requests from libcamera's thread (the requestCompleted
// signal) to the thread that converts and re-queues them.

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>

#include <libcamera/request.h>

namespace cblox {

/// A FIFO of completed requests (not owned) with a blocking, timed pop, and a "closed" state
/// for a camera that went away. Thread-safe: every member may be called from any thread.
class CompletedRequestQueue {
 public:
  enum class PopResult { kRequest, kTimeout, kClosed };

  /// Appends a completed request and wakes a waiting pop(). Never blocks for long (the
  /// signal handler calls it on libcamera's thread). Thread-safe.
  void push(libcamera::Request* request);

  /// Waits up to `timeout` for a request and moves the oldest into *request (non-null):
  /// kRequest. kTimeout when none came in time. kClosed when the queue is empty and close()
  /// was called (requests pushed before close() are still handed out first). Thread-safe.
  PopResult pop(std::chrono::nanoseconds timeout, libcamera::Request** request);

  /// Marks the queue closed (the camera was disconnected) and wakes every waiter.
  /// Thread-safe.
  void close();

  /// Forgets every queued request and reopens the queue. Thread-safe.
  void clear();

  /// Requests waiting. Thread-safe.
  size_t size() const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<libcamera::Request*> requests_;
  bool closed_ = false;
};

}  // namespace cblox
