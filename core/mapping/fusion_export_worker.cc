#include "core/mapping/fusion_export_worker.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <utility>

#include "core/common/thread_name.h"
#include "core/common/thread_priority.h"
#include "core/submap/submap_fusion.h"

namespace cblox {

FusionExportWorker::FusionExportWorker(SubmapCollection* collection,
                                       FusionExportWorkerConfig config, FusionCallback on_fusion,
                                       LogSink log)
    : collection_(collection),
      config_(std::move(config)),
      on_fusion_(std::move(on_fusion)),
      log_(std::move(log)) {}

FusionExportWorker::~FusionExportWorker() { stop(); }

void FusionExportWorker::start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (started_) return;
  started_ = true;
  for (Periodic& p : periodic_) p.due = std::chrono::steady_clock::now() + p.period;
  thread_ = std::thread([this] {
    nameThisThread("cblox-export");
    loop();
  });
}

void FusionExportWorker::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stop_) return;
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  // Not started, or stopped: answer what is still queued.
  std::deque<QueuedCommand> left;
  size_t fusions_left = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    left.swap(commands_);
    fusions_left = fusions_.size();
    fusions_.clear();
  }
  if (fusions_left > 0) {
    log_("stopping: " + std::to_string(fusions_left) + " accepted fusion(s) not done");
  }
  for (QueuedCommand& queued : left) {
    MapperReply reply;
    reply.id = queued.command.id;
    reply.ok = false;
    reply.message = "mapper stopping";
    if (queued.reply) queued.reply(reply);
  }
}

void FusionExportWorker::submitExport(MapperCommand command, ReplyCallback reply) {
  submitJob(std::move(command), nullptr, std::move(reply));
}

void FusionExportWorker::submitJob(MapperCommand command, Job job, ReplyCallback reply) {
  bool queued = false, stopping = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping = stop_;
    if (!stopping && commands_.size() < config_.command_queue_capacity) {
      commands_.push_back(QueuedCommand{std::move(command), std::move(reply), std::move(job)});
      queued = true;
    }
  }
  if (queued) {
    cv_.notify_all();
    return;
  }
  MapperReply r;
  r.id = command.id;
  r.ok = false;
  r.message = stopping ? "mapper stopping" : "busy: too many commands waiting, try again later";
  if (reply) reply(r);
}

void FusionExportWorker::addPeriodicTask(double period_s, PeriodicTask task) {
  std::lock_guard<std::mutex> lock(mutex_);
  Periodic p;
  p.period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(period_s));
  p.task = std::move(task);
  periodic_.push_back(std::move(p));
}

FusionExportWorker::Periodic* FusionExportWorker::duePeriodic() {
  const auto now = std::chrono::steady_clock::now();
  for (Periodic& p : periodic_) {
    if (now >= p.due) return &p;
  }
  return nullptr;
}

void FusionExportWorker::submitFusions(const std::vector<FusionPair>& pairs) {
  if (pairs.empty()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stop_) return;
    fusions_.insert(fusions_.end(), pairs.begin(), pairs.end());
  }
  cv_.notify_all();
}

bool FusionExportWorker::idle() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return commands_.empty() && fusions_.empty() && !busy_;
}

void FusionExportWorker::lowerPriority() {
  if (const std::string problem = lowerThreadPriority(config_.niceness, config_.sched_idle);
      !problem.empty()) {
    log_("worker: " + problem);
  }
}

void FusionExportWorker::loop() {
  lowerPriority();
  std::unique_lock<std::mutex> lock(mutex_);
  const auto has_work = [this] { return stop_ || !commands_.empty() || !fusions_.empty(); };
  while (true) {
    if (!periodic_.empty()) {
      auto next = periodic_.front().due;
      for (const Periodic& p : periodic_) next = std::min(next, p.due);
      cv_.wait_until(lock, next, has_work);
    } else {
      cv_.wait(lock, has_work);
    }
    if (stop_) break;
    Periodic* const periodic = duePeriodic();
    if (commands_.empty() && fusions_.empty() && periodic == nullptr) continue;
    busy_ = true;
    if (commands_.empty() && periodic != nullptr) {  // after the commands, before the fusions
      periodic->due = std::chrono::steady_clock::now() + periodic->period;
      const PeriodicTask task = periodic->task;
      lock.unlock();
      task();
    } else if (commands_.empty()) {  // commands first: an operator is waiting for them
      const FusionPair pair = fusions_.front();
      fusions_.pop_front();
      lock.unlock();
      fuse(pair);
    } else {
      QueuedCommand queued = std::move(commands_.front());
      commands_.pop_front();
      lock.unlock();
      runCommand(queued);
    }
    lock.lock();
    busy_ = false;
  }
}

void FusionExportWorker::runCommand(QueuedCommand& queued) {
  MapperReply reply;
  try {
    if (queued.job) {
      reply = queued.job();
    } else {
      const std::string& path = queued.command.args.at("path");
      reply = queued.command.name == "export_mesh"
                  ? exportGlobalMesh(*collection_, config_.exports, config_.output_dir, path)
                  : exportSubvolumeMeshes(*collection_, config_.exports, config_.output_dir, path);
    }
  } catch (const std::exception& e) {
    reply = MapperReply{};
    reply.ok = false;
    reply.message = queued.command.name + " failed: " + e.what();
  }
  reply.id = queued.command.id;
  if (!queued.job) {
    (reply.ok ? exports_done_ : exports_failed_).fetch_add(1, std::memory_order_relaxed);
  }
  log_(queued.command.name + ": " + reply.message);
  if (queued.reply) queued.reply(reply);
}

void FusionExportWorker::fuse(const FusionPair& pair) {
  const std::shared_ptr<Submap> older = collection_->getSubmap(pair.older);
  const std::shared_ptr<Submap> newer = collection_->getSubmap(pair.newer);
  // A subvolume that is no longer the collection's active one is being finished by the thread
  // that replaced it (SubmapCollection::createSubmap makes the new one active, then finishes
  // the previous one outside its lock, waiting for the frame in hand). Finish it here too
  // (idempotent, the same wait) rather than fail the pair for that moment.
  const std::shared_ptr<Submap> active = collection_->activeSubmap();
  const auto finished = [&active](Submap& submap) {
    if (!submap.isFinished() && &submap != active.get()) submap.finish();
    return submap.isFinished();
  };
  std::string failure;
  if (!older || !newer) {
    failure = "a subvolume of the pair no longer exists";
  } else if (!finished(*older) || !finished(*newer)) {
    failure = "a subvolume of the pair is still active";
  } else {
    try {
      const SubmapFusionStats stats = fuseSubmaps(*newer, older.get(), config_.exports.fusion);
      collection_->removeSubmap(pair.newer);
      if (on_fusion_) on_fusion_(pair, true);
      char line[200];
      std::snprintf(line, sizeof(line),
                    "fused subvolume %lld into %lld (%d shared landmarks): %zu voxels in %.0f ms",
                    static_cast<long long>(pair.newer), static_cast<long long>(pair.older),
                    pair.shared_landmarks, stats.voxels_fused, stats.seconds * 1e3);
      log_(line);
      return;
    } catch (const std::exception& e) {
      failure = e.what();
    }
  }
  if (on_fusion_) on_fusion_(pair, false);
  log_("fusion of subvolume " + std::to_string(pair.newer) + " into " + std::to_string(pair.older) +
       " not done: " + failure);
}

}  // namespace cblox
