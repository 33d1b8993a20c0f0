#pragma once

// Runs short jobs on a thread of its own at a set priority, for a caller of lower priority
// that must not hold a lock others wait for: the mapper's idle-priority worker copies the
// active subvolume's changed blocks this way, so the integrator never waits on a lock held by
// a thread the scheduler may not run for a long time (priority inversion).

#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace cblox {

/// One thread (named `name`, at niceness `niceness` 0..19, normal scheduling) that runs the
/// jobs handed to run(), one at a time, while their callers wait.
/// Thread-safety: run() from any thread (callers take turns); start() and stop() from one.
class PriorityRunner {
 public:
  PriorityRunner(std::string name, int niceness);
  /// Calls stop().
  ~PriorityRunner();
  PriorityRunner(const PriorityRunner&) = delete;
  PriorityRunner& operator=(const PriorityRunner&) = delete;

  void start();
  /// Finishes the job in hand; later run() calls return false. Idempotent.
  void stop();
  /// Runs `job` on the runner's thread and waits for it. False (job not run) when the runner
  /// is not running. `job` must not throw and must not call run().
  bool run(const std::function<void()>& job);

 private:
  const std::string name_;
  const int niceness_;
  std::mutex call_mutex_;  // one caller at a time
  std::mutex mutex_;       // guards the fields below
  std::condition_variable cv_;
  const std::function<void()>* job_ = nullptr;
  bool done_ = false, stop_ = false, running_ = false;
  std::thread thread_;
};

}  // namespace cblox
