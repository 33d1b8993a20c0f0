#pragma once

// The mapper's fusion / export worker: one low-priority thread that is the single owner of
// finished subvolume layers (SubmapCollection's rule). It runs commands first (exports, map
// saves and loads: an operator is waiting), then the fusions map maintenance accepted.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/maintenance/fusion_scheduler.h"
#include "core/mapping/map_export.h"
#include "core/mapping/mapper_command.h"
#include "core/submap/submap_collection.h"

namespace cblox {

/// Settings of the worker (from MapperConfig). Plain value type.
struct FusionExportWorkerConfig {
  MapExportConfig exports;
  /// Exports are confined to this directory (absolute).
  std::filesystem::path output_dir;
  /// Export commands waiting (more are answered "busy"), >= 1.
  size_t command_queue_capacity = 4;
  /// Niceness of the thread (setpriority on its thread id), [0, 19], and SCHED_IDLE.
  int niceness = 10;
  bool sched_idle = true;
};

/// Fuses accepted pairs (the newer subvolume into the older: fuseSubmaps, then the newer is
/// removed from the collection) and runs export commands, on its own thread.
/// Both subvolumes of a pair must be finished (an active one is never fused); one that is no
/// longer the collection's active subvolume but not yet finished (its replacement is being
/// created) is finished by the worker first, which waits for the frame being integrated.
/// An export holds the ACTIVE subvolume's layer lock only while copying that layer.
/// Thread-safety: every public member function is thread-safe; callbacks run on the worker
/// thread (an export reply also on the caller's, when it is refused at once).
class FusionExportWorker {
 public:
  using ReplyCallback = std::function<void(const MapperReply&)>;
  using LogSink = std::function<void(const std::string&)>;
  /// After each pair: whether it was fused (false: not done, and logged why).
  using FusionCallback = std::function<void(const FusionPair& pair, bool fused)>;
  /// A command the submitter carries out itself on the worker thread (save_map, load_map:
  /// they run where fusions run, so no fusion changes the map meanwhile); returns the reply.
  using Job = std::function<MapperReply()>;
  /// Work the worker does on its own schedule (the mapper's periodic checkpoint, the planning
  /// map's refresh).
  using PeriodicTask = std::function<void()>;

  /// `collection` must outlive the worker.
  FusionExportWorker(SubmapCollection* collection, FusionExportWorkerConfig config,
                     FusionCallback on_fusion, LogSink log);
  /// Calls stop().
  ~FusionExportWorker();
  FusionExportWorker(const FusionExportWorker&) = delete;
  FusionExportWorker& operator=(const FusionExportWorker&) = delete;

  /// Starts the thread. Call once.
  void start();
  /// Finishes the export or fusion in hand, answers queued exports "mapper stopping", leaves
  /// queued fusions undone (logged; both subvolumes stay), joins. Idempotent.
  void stop();

  /// Queues "export_mesh" or "export_submap_meshes" {path} (checked by the caller); when the
  /// queue is full or the worker stopping, `reply` is called at once with ok = false.
  void submitExport(MapperCommand command, ReplyCallback reply);
  /// Queues `command` (checked by the caller) to be carried out by `job` on the worker
  /// thread, in the same queue as the exports and with the same refusals (queue full,
  /// stopping: `reply` at once with ok = false). `reply` gets the job's reply with the
  /// command's id; a job that throws is answered ok = false with the exception's message.
  /// Jobs are not counted in exportsDone() / exportsFailed().
  void submitJob(MapperCommand command, Job job, ReplyCallback reply);
  /// Runs `task` on the worker thread every `period_s` seconds (> 0, finite), the first time
  /// `period_s` after start(): when due, it goes after the commands waiting and before the
  /// fusions (a backlog of fusions does not delay it); of several due tasks, the one added
  /// first goes first. The next one is due `period_s` after the previous one began (none is
  /// made up for). The task in hand finishes before stop() returns; while it runs, idle() is
  /// false. `task` must not throw. Call before start().
  void addPeriodicTask(double period_s, PeriodicTask task);
  /// Queues pairs for fusion (ignored once stopping).
  void submitFusions(const std::vector<FusionPair>& pairs);

  /// Nothing queued and nothing in hand.
  bool idle() const;
  uint64_t exportsDone() const { return exports_done_.load(); }
  uint64_t exportsFailed() const { return exports_failed_.load(); }

 private:
  struct QueuedCommand {
    MapperCommand command;
    ReplyCallback reply;
    Job job;  // empty for the exports
  };
  void loop();
  void lowerPriority();
  void fuse(const FusionPair& pair);
  void runCommand(QueuedCommand& queued);

  SubmapCollection* const collection_;
  const FusionExportWorkerConfig config_;
  const FusionCallback on_fusion_;
  const LogSink log_;

  mutable std::mutex mutex_;  // guards the queues and the flags
  std::condition_variable cv_;
  std::deque<QueuedCommand> commands_;
  std::deque<FusionPair> fusions_;
  bool busy_ = false, stop_ = false, started_ = false;
  struct Periodic {
    std::chrono::steady_clock::duration period{};
    PeriodicTask task;
    std::chrono::steady_clock::time_point due;
  };
  // The first due periodic task, or null. Call with mutex_ held.
  Periodic* duePeriodic();
  std::vector<Periodic> periodic_;
  std::thread thread_;
  std::atomic<uint64_t> exports_done_{0}, exports_failed_{0};
};

}  // namespace cblox
