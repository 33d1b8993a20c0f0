#include "core/mapping/active_field_refresher.h"

#include "core/common/thread_name.h"
#include "core/common/thread_priority.h"

namespace cblox {

ActiveFieldRefresher::ActiveFieldRefresher(PlanningMap* planning,
                                           const SubmapCollection* collection, double period_s,
                                           int niceness)
    : planning_(planning),
      collection_(collection),
      period_(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double>(period_s))),
      niceness_(niceness) {}

ActiveFieldRefresher::~ActiveFieldRefresher() { stop(); }

void ActiveFieldRefresher::start() {
  if (thread_.joinable()) return;
  thread_ = std::thread([this] {
    nameThisThread("cblox-esdf");
    if (niceness_ > 0) lowerThreadPriority(niceness_, false);
    std::unique_lock<std::mutex> lock(mutex_);
    while (!stop_) {
      if (wake_.wait_for(lock, period_, [this] { return stop_; })) break;
      lock.unlock();
      planning_->refreshActive(*collection_);
      lock.lock();
    }
  });
}

void ActiveFieldRefresher::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

}  // namespace cblox
