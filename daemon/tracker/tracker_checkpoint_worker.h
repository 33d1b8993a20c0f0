#pragma once

// The tracker's checkpoint writer: a low-priority thread that, every period, takes a snapshot
// of the sparse map (through the node) and writes it incrementally into the checkpoint
// directory (core/persistence/tracker_map_checkpointer.h); a last checkpoint when it stops.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "core/persistence/tracker_map_checkpointer.h"

namespace cblox {

/// Counters of the checkpoints written. Plain value type.
struct TrackerCheckpointStats {
  uint64_t written = 0;
  uint64_t failures = 0;
  uint64_t generation = 0;  ///< of the last committed checkpoint (0: none yet)
  double last_ms = 0.0;     ///< wall time of the last checkpoint
  uint64_t last_bytes = 0;
  uint64_t last_keyframes_written = 0;
};

/// Thread-safety: start / stop from one thread; stats() from any.
class TrackerCheckpointWorker {
 public:
  /// The map to save now, or std::nullopt when there is none yet. Called on the worker thread.
  using SnapshotSource = std::function<std::optional<TrackerMapState>()>;
  using Log = std::function<void(const std::string&)>;

  /// `period_s` > 0: periodic checkpoints; 0: only the last one in stop().
  TrackerCheckpointWorker(TrackerMapCheckpointer checkpointer, double period_s,
                          SnapshotSource source, Log log);
  ~TrackerCheckpointWorker();
  TrackerCheckpointWorker(const TrackerCheckpointWorker&) = delete;
  TrackerCheckpointWorker& operator=(const TrackerCheckpointWorker&) = delete;

  /// Starts the thread (niceness 10).
  void start();
  /// Stops the thread and writes a last checkpoint (on the caller's thread). Idempotent.
  void stop();
  /// Writes a checkpoint now on the caller's thread (serialized with the worker's).
  bool checkpointNow();

  TrackerCheckpointStats stats() const;

 private:
  void loop();

  SnapshotSource source_;
  Log log_;
  std::chrono::duration<double> period_;
  std::mutex write_mutex_;  // one checkpoint at a time; guards checkpointer_
  TrackerMapCheckpointer checkpointer_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  bool stop_ = false, stopped_ = false;
  TrackerCheckpointStats stats_;
  std::thread thread_;
};

}  // namespace cblox
