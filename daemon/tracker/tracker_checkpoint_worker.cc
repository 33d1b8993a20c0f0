#include "daemon/tracker/tracker_checkpoint_worker.h"

#include <cstdio>
#include <utility>

#include "core/common/thread_name.h"
#include "core/common/thread_priority.h"

namespace cblox {

TrackerCheckpointWorker::TrackerCheckpointWorker(TrackerMapCheckpointer checkpointer,
                                                 double period_s, SnapshotSource source, Log log)
    : source_(std::move(source)),
      log_(std::move(log)),
      period_(period_s),
      checkpointer_(std::move(checkpointer)) {}

TrackerCheckpointWorker::~TrackerCheckpointWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void TrackerCheckpointWorker::start() {
  if (period_.count() > 0.0) {
    thread_ = std::thread([this] {
      nameThisThread("cblox-checkpt");
      loop();
    });
  }
}

void TrackerCheckpointWorker::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopped_) return;
    stopped_ = stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  checkpointNow();
}

TrackerCheckpointStats TrackerCheckpointWorker::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

bool TrackerCheckpointWorker::checkpointNow() {
  std::lock_guard<std::mutex> write_lock(write_mutex_);
  const std::optional<TrackerMapState> state = source_();
  if (!state) return true;  // no map yet: nothing to save
  std::string error;
  const std::optional<TrackerCheckpointReport> report = checkpointer_.checkpoint(*state, &error);
  std::lock_guard<std::mutex> lock(mutex_);
  if (!report) {
    ++stats_.failures;
    log_("checkpoint failed: " + error);
    return false;
  }
  ++stats_.written;
  stats_.generation = report->generation;
  stats_.last_ms = report->milliseconds;
  stats_.last_bytes = report->bytes_written;
  stats_.last_keyframes_written = report->keyframes_written;
  return true;
}

void TrackerCheckpointWorker::loop() {
  // Nice 10, not SCHED_IDLE: on a loaded machine SCHED_IDLE can starve the thread for
  // minutes, and every minute without a checkpoint is what a kill would lose.
  if (const std::string problem = lowerThreadPriority(10, false); !problem.empty()) {
    log_("checkpoint worker: " + problem);
  }
  auto due = std::chrono::steady_clock::now() +
             std::chrono::duration_cast<std::chrono::steady_clock::duration>(period_);
  while (true) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (cv_.wait_until(lock, due, [this] { return stop_; })) return;
    }
    checkpointNow();
    due = std::chrono::steady_clock::now() +
          std::chrono::duration_cast<std::chrono::steady_clock::duration>(period_);
  }
}

}  // namespace cblox
