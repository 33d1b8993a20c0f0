#pragma once

// The mapper's "cblox-esdf" thread: the active subvolume's distance field follows
// integration every period (PlanningMap::refreshActive), at the integrator's priority.

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "core/mapping/planning_map.h"
#include "core/submap/submap_collection.h"

namespace cblox {

/// Calls planning->refreshActive(*collection) every `period_s` on a thread of its own (niceness
/// `niceness`, 0..19), from start() until stop(). Thread-safety: start() and stop() from one
/// thread; `planning` and `collection` must outlive it.
class ActiveFieldRefresher {
 public:
  ActiveFieldRefresher(PlanningMap* planning, const SubmapCollection* collection, double period_s,
                       int niceness);
  ~ActiveFieldRefresher();
  ActiveFieldRefresher(const ActiveFieldRefresher&) = delete;
  ActiveFieldRefresher& operator=(const ActiveFieldRefresher&) = delete;

  void start();
  /// Waits for a refresh in hand to finish.
  void stop();

 private:
  PlanningMap* const planning_;
  const SubmapCollection* const collection_;
  const std::chrono::steady_clock::duration period_;
  const int niceness_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace cblox
