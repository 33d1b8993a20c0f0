#include "drivers/libcamera/completed_request_queue.h"

namespace cblox {

void CompletedRequestQueue::push(libcamera::Request* request) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    requests_.push_back(request);
  }
  ready_.notify_one();
}

CompletedRequestQueue::PopResult CompletedRequestQueue::pop(std::chrono::nanoseconds timeout,
                                                            libcamera::Request** request) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (!ready_.wait_for(lock, timeout, [this] { return !requests_.empty() || closed_; })) {
    return PopResult::kTimeout;
  }
  if (requests_.empty()) return PopResult::kClosed;
  *request = requests_.front();
  requests_.pop_front();
  return PopResult::kRequest;
}

void CompletedRequestQueue::close() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
  }
  ready_.notify_all();
}

void CompletedRequestQueue::clear() {
  const std::lock_guard<std::mutex> lock(mutex_);
  requests_.clear();
  closed_ = false;
}

size_t CompletedRequestQueue::size() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return requests_.size();
}

}  // namespace cblox
