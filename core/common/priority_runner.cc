#include "core/common/priority_runner.h"

#include <utility>

#include "core/common/thread_name.h"
#include "core/common/thread_priority.h"

namespace cblox {

PriorityRunner::PriorityRunner(std::string name, int niceness)
    : name_(std::move(name)), niceness_(niceness) {}

PriorityRunner::~PriorityRunner() { stop(); }

void PriorityRunner::start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (running_ || stop_) return;
  running_ = true;
  thread_ = std::thread([this] {
    nameThisThread(name_.c_str());
    if (niceness_ > 0) lowerThreadPriority(niceness_, false);
    std::unique_lock<std::mutex> held(mutex_);
    for (;;) {
      cv_.wait(held, [this] { return stop_ || job_ != nullptr; });
      if (job_ != nullptr) {
        const std::function<void()>* job = job_;
        held.unlock();
        (*job)();
        held.lock();
        job_ = nullptr;
        done_ = true;
        cv_.notify_all();
        continue;
      }
      if (stop_) return;
    }
  });
}

void PriorityRunner::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  std::lock_guard<std::mutex> lock(mutex_);
  running_ = false;
}

bool PriorityRunner::run(const std::function<void()>& job) {
  std::lock_guard<std::mutex> call(call_mutex_);
  std::unique_lock<std::mutex> lock(mutex_);
  if (!running_ || stop_) return false;
  job_ = &job;
  done_ = false;
  cv_.notify_all();
  cv_.wait(lock, [this] { return done_; });
  return true;
}

}  // namespace cblox
