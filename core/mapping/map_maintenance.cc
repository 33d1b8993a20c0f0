#include "core/mapping/map_maintenance.h"

#include <algorithm>
#include <exception>
#include <optional>

#include "core/common/text_format.h"
#include "core/common/thread_name.h"
#include "core/common/utime_ns.h"
#include "core/mapping/map_epoch_key.h"

namespace cblox {

MapMaintenance::MapMaintenance(MapMaintenanceConfig config, SubmapCollection* collection,
                               SubmapCreationPolicy* policy, std::mutex* policy_mutex,
                               FusionExportWorker* worker, ProblemSink problems, LogSink log)
    : config_(std::move(config)),
      collection_(collection),
      policy_(policy),
      policy_mutex_(policy_mutex),
      worker_(worker),
      problems_(std::move(problems)),
      log_(std::move(log)),
      scheduler_(config_.scheduler) {}

MapMaintenance::~MapMaintenance() { stop(); }

void MapMaintenance::setCovarianceRequester(CovarianceRequester requester) {
  covariance_requester_ = std::move(requester);
}

void MapMaintenance::setPosesMovedCallback(std::function<void()> callback) {
  poses_moved_ = std::move(callback);
}

void MapMaintenance::start() {
  std::lock_guard<std::mutex> lock(queue_mutex_);
  if (started_) return;
  started_ = true;
  thread_ = std::thread([this] {
    nameThisThread("cblox-maintain");
    loop();
  });
}

void MapMaintenance::stop() {
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    if (stopped_) return;
    stopped_ = true;
    stop_ = true;
  }
  queue_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  // Keyframes and pose batches still queued are applied (no voxel is touched, so this is
  // quick and bounded by the queue's capacity), so the map's frames are final.
  std::deque<Item> left;
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    left.swap(queue_);
  }
  for (const Item& item : left) apply(item);
  if (!left.empty()) {
    log_("stopping: applied " + std::to_string(left.size()) +
         " queued keyframe / pose-batch message(s)");
  }
}

bool MapMaintenance::enqueue(Item item) {
  bool dropped = false;
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    if (stop_) return false;
    queue_.push_back(std::move(item));
    if (queue_.size() > config_.queue_capacity) {
      // Never a synthesised keyframe: its frame waits for it.
      const auto oldest = std::find_if(queue_.begin(), queue_.end(), [](const Item& i) {
        return i.kind != Item::Kind::kSynthesisedKeyframe;
      });
      if (oldest != queue_.end()) {
        queue_.erase(oldest);
        dropped = true;
      }
    }
  }
  queue_cv_.notify_all();
  if (dropped)
    problems_(InputProblem::kMaintenanceDropped, "maintenance queue full: oldest dropped", 1);
  return true;
}

void MapMaintenance::enqueueKeyframe(KeyframeId id, int64_t utime, const Transformationd& T_G_K,
                                     std::vector<uint64_t> landmark_ids) {
  Item item;
  item.keyframe_id = id;
  item.utime = utime;
  item.T_G_K = T_G_K;
  item.landmark_ids = std::move(landmark_ids);
  enqueue(std::move(item));
}

void MapMaintenance::enqueueBatch(std::vector<std::pair<KeyframeId, Transformationd>> T_G_K) {
  Item item;
  item.kind = Item::Kind::kBatch;
  item.batch = std::move(T_G_K);
  enqueue(std::move(item));
}

void MapMaintenance::enqueueReply(int64_t request_id, std::vector<FusionCovarianceAnswer> answers) {
  Item item;
  item.kind = Item::Kind::kCovarianceReply;
  item.request_id = request_id;
  item.answers = std::move(answers);
  enqueue(std::move(item));
}

bool MapMaintenance::applySynthesisedKeyframe(KeyframeId id, int64_t utime,
                                              const Transformationd& T_G_K) {
  Item item;
  item.kind = Item::Kind::kSynthesisedKeyframe;
  item.keyframe_id = id;
  item.utime = utime;
  item.T_G_K = T_G_K;
  item.applied = std::make_shared<std::promise<void>>();
  std::future<void> applied = item.applied->get_future();
  if (!enqueue(std::move(item))) return false;
  applied.wait();  // set after it is applied, also by stop()
  return true;
}

void MapMaintenance::tick() {
  {
    // A queued item is followed by scheduleFusions anyway; a tick never displaces one.
    std::lock_guard<std::mutex> lock(queue_mutex_);
    if (stop_ || !queue_.empty()) return;
  }
  Item item;
  item.kind = Item::Kind::kTick;
  enqueue(std::move(item));
}

void MapMaintenance::loop() {
  std::unique_lock<std::mutex> lock(queue_mutex_);
  while (true) {
    // The 0.25 s tick lets a timed-out covariance request be followed by a new one; on the
    // input clock a request follows inputs only.
    const auto ready = [this] { return stop_ || !queue_.empty(); };
    if (config_.clock == MaintenanceClock::kInput) {
      queue_cv_.wait(lock, ready);
    } else {
      queue_cv_.wait_for(lock, std::chrono::milliseconds(250), ready);
    }
    if (stop_) break;
    if (queue_.empty()) {
      lock.unlock();
      scheduleFusions();
      lock.lock();
      continue;
    }
    Item item = std::move(queue_.front());
    queue_.pop_front();
    busy_ = true;
    lock.unlock();
    apply(item);
    scheduleFusions();
    lock.lock();
    busy_ = false;
  }
}

void MapMaintenance::apply(const Item& item) {
  using Kind = Item::Kind;
  try {
    switch (item.kind) {
      case Kind::kBatch:
        applyBatch(item.batch);
        break;
      case Kind::kKeyframe:
        applyKeyframe(item.keyframe_id, item.utime, item.T_G_K, false, item.landmark_ids);
        break;
      case Kind::kSynthesisedKeyframe:
        applyKeyframe(item.keyframe_id, item.utime, item.T_G_K, true, {});
        break;
      case Kind::kCovarianceReply:
        applyReply(item);
        break;
      case Kind::kTick:  // scheduleFusions follows every item
        break;
    }
  } catch (const std::exception& e) {
    problems_(item.kind == Kind::kBatch             ? InputProblem::kKeyframePoseInvalid
              : item.kind == Kind::kCovarianceReply ? InputProblem::kCovarianceReplyInvalid
                                                    : InputProblem::kKeyframeInvalid,
              e.what(), 1);
  }
  if (item.applied) item.applied->set_value();
}

void MapMaintenance::applyKeyframe(KeyframeId id, int64_t utime, const Transformationd& T_G_K,
                                   bool synthesised, std::span<const uint64_t> landmark_ids) {
  std::shared_ptr<Submap> created;
  SubmapId joined = -1;
  SubmapCreationPolicy::Reason reason = SubmapCreationPolicy::Reason::kNone;
  {
    std::lock_guard<std::mutex> lock(*policy_mutex_);
    if (synthesised && keyframes_seen_.count(id) > 0) id = max_keyframe_seen_ + 1;
    max_keyframe_seen_ = std::max(max_keyframe_seen_, id);
    if (!keyframes_seen_.insert(id).second) {
      problems_(InputProblem::kKeyframeDuplicate,
                "keyframe " + std::to_string(id) + ": id already applied", 1);
      return;
    }
    std::shared_ptr<Submap> active = collection_->activeSubmap();
    // A keyframe of another map epoch (map_epoch_key.h: the tracker started a new map) never
    // joins a subvolume of the old map: the two maps' frames are unrelated.
    const bool new_map = active && epochOfKey(id) != epochOfKey(active->anchorKeyframe());
    // Revisit anchoring compares with the other subvolumes' anchors of this map epoch.
    std::vector<Eigen::Vector3d> older_anchors;
    if (policy_->config().revisit_anchor_distance_m > 0.0) {
      for (const SubmapPose& pose : collection_->poseSnapshot()) {
        if (pose.active || epochOfKey(pose.anchor_keyframe) != epochOfKey(id)) continue;
        older_anchors.push_back(pose.T_G_M.translation());
      }
    }
    if (policy_->onKeyframe(active.get(), new_map, T_G_K.translation(), older_anchors)) {
      // Finishes the previous submap (waits for the frame being integrated into it).
      // Clamped: a keyframe time stamp from the bus beyond +-292 years overflows in ns.
      reason = policy_->lastReason();
      created = collection_->createSubmap(T_G_K, id, utimeToNs(utime));
      joined = created->id();
    } else {
      active->addKeyframe(id);
      joined = active->id();
    }
  }
  {
    std::lock_guard<std::mutex> lock(scheduler_mutex_);
    if (created) scheduler_.addSubvolume(created->id(), id);
    scheduler_.addKeyframeLandmarks(joined, id, landmark_ids);
  }
  keyframes_applied_.fetch_add(1, std::memory_order_relaxed);
  if (created) {
    log_("subvolume " + std::to_string(created->id()) + " anchored at keyframe " +
         std::to_string(idOfKey(id)) +
         (epochOfKey(id) > 0 ? " of map epoch " + std::to_string(epochOfKey(id)) : "") + " (" +
         SubmapCreationPolicy::reasonName(reason) + ")");
  }
}

void MapMaintenance::applyBatch(const std::vector<std::pair<KeyframeId, Transformationd>>& batch) {
  const KeyframePoseUpdateResult result = collection_->updateKeyframePoses(batch);
  keyframe_batches_.fetch_add(1, std::memory_order_relaxed);
  submaps_moved_.fetch_add(result.submaps_moved, std::memory_order_relaxed);
  if (result.submaps_moved > 0 && poses_moved_) poses_moved_();
  problems_(InputProblem::kKeyframePoseUnknown,
            std::to_string(result.keyframes_unknown) + " of " + std::to_string(batch.size()) +
                " keyframe poses in a batch name keyframes no subvolume knows",
            result.keyframes_unknown);
  problems_(InputProblem::kKeyframePoseInvalid,
            std::to_string(result.poses_invalid) + " of " + std::to_string(batch.size()) +
                " keyframe poses in a batch are not finite",
            result.poses_invalid);
}

double MapMaintenance::seconds() const {
  if (config_.clock == MaintenanceClock::kInput) {
    return static_cast<double>(input_clock_us_.load()) * 1e-6;
  }
  return secondsSince(start_time_);
}

void MapMaintenance::advanceInputClock(int64_t utime) {
  std::lock_guard<std::mutex> lock(input_clock_mutex_);
  if (last_input_utime_ != INT64_MIN && utime > last_input_utime_) {
    // Unsigned: two time stamps from the bus may be more than INT64_MAX apart.
    const uint64_t step = static_cast<uint64_t>(utime) - static_cast<uint64_t>(last_input_utime_);
    input_clock_us_.fetch_add(static_cast<int64_t>(std::min<uint64_t>(step, INT64_MAX)));
  }
  // A restarted source's time stamps start a new base; small steps back keep the newest.
  if (utime > last_input_utime_ ||
      isTimeRestart(last_input_utime_, utime, config_.restart_after_backwards_s)) {
    last_input_utime_ = utime;
  }
}

size_t MapMaintenance::adoptLoadedSubmaps(const std::vector<std::shared_ptr<Submap>>& submaps,
                                          const FusionSchedulerState& state) {
  // *policy_mutex_ is held by the caller (keyframes_seen_).
  for (const std::shared_ptr<Submap>& submap : submaps) {
    for (const KeyframeId id : submap->keyframeIds()) {
      keyframes_seen_.insert(id);
      max_keyframe_seen_ = std::max(max_keyframe_seen_, id);
    }
  }
  std::lock_guard<std::mutex> lock(scheduler_mutex_);
  for (const std::shared_ptr<Submap>& submap : submaps) {
    scheduler_.addSubvolume(submap->id(), submap->anchorKeyframe());
  }
  return scheduler_.restoreState(state, seconds());
}

FusionSchedulerState MapMaintenance::schedulerState() const {
  std::lock_guard<std::mutex> lock(scheduler_mutex_);
  return scheduler_.exportState(seconds());
}

void MapMaintenance::scheduleFusions() {
  std::vector<FusionPair> exact;
  std::optional<FusionCovarianceRequest> request;
  {
    std::lock_guard<std::mutex> lock(scheduler_mutex_);
    const std::shared_ptr<Submap> active = collection_->activeSubmap();
    const SubmapId active_id = active ? active->id() : -1;
    exact = scheduler_.takeSameAnchorPairs(active_id);
    if (covariance_requester_) request = scheduler_.nextRequest(active_id, seconds());
  }
  submitSameAnchorPairs(exact);
  if (request) covariance_requester_(*request);
}

void MapMaintenance::submitSameAnchorPairs(const std::vector<FusionPair>& pairs) {
  for (const FusionPair& pair : pairs) {
    const bool same = pair.older_keyframe == pair.newer_keyframe;
    log_("fusion accepted: subvolume " + std::to_string(pair.newer) + " into " +
         std::to_string(pair.older) + " without a covariance (" +
         (same ? "both anchored at keyframe " + std::to_string(idOfKey(pair.older_keyframe))
               : "anchored at keyframe " + std::to_string(idOfKey(pair.newer_keyframe)) +
                     ", whose subvolume was fused into it") +
         ")");
  }
  if (!pairs.empty()) worker_->submitFusions(pairs);
}

void MapMaintenance::adoptRevisitSubmap(SubmapId revisit, SubmapId home, KeyframeId anchor,
                                        SubmapCreationPolicy::Reason reason) {
  std::vector<FusionPair> exact;
  {
    std::lock_guard<std::mutex> lock(scheduler_mutex_);
    scheduler_.addSubvolumeSharingAnchor(revisit, home);
    // The submap it replaced as the active one may now pair with one sharing its anchor.
    exact = scheduler_.takeSameAnchorPairs(revisit);
  }
  log_("subvolume " + std::to_string(revisit) + " anchored at keyframe " +
       std::to_string(idOfKey(anchor)) +
       (epochOfKey(anchor) > 0 ? " of map epoch " + std::to_string(epochOfKey(anchor)) : "") +
       " (" + SubmapCreationPolicy::reasonName(reason) + ": revisit of subvolume " +
       std::to_string(home) + ")");
  submitSameAnchorPairs(exact);
}

void MapMaintenance::applyReply(const Item& item) {
  std::vector<FusionPair> accepted;
  {
    std::lock_guard<std::mutex> lock(scheduler_mutex_);
    accepted = scheduler_.onReply(item.request_id, item.answers, seconds());
  }
  for (const FusionPair& pair : accepted) {
    log_("fusion accepted: subvolume " + std::to_string(pair.newer) + " into " +
         std::to_string(pair.older) + " (keyframe " + std::to_string(idOfKey(pair.newer_keyframe)) +
         " given " + std::to_string(idOfKey(pair.older_keyframe)) + ", " +
         std::to_string(pair.keyframe_shared_landmarks) + " landmarks in common)");
  }
  worker_->submitFusions(accepted);
}

void MapMaintenance::onFusionResult(const FusionPair& pair, bool fused) {
  std::lock_guard<std::mutex> lock(scheduler_mutex_);
  if (fused) {
    scheduler_.onFused(pair);
  } else {
    scheduler_.onFusionFailed(pair, seconds());
  }
}

bool MapMaintenance::idle() const {
  std::lock_guard<std::mutex> lock(queue_mutex_);
  return queue_.empty() && !busy_;
}

FusionSchedulerStats MapMaintenance::schedulerStats() const {
  std::lock_guard<std::mutex> lock(scheduler_mutex_);
  return scheduler_.stats();
}

std::vector<CovisibilityCandidate> MapMaintenance::covisibilityEdges() const {
  CovisibilityGraphConfig all;
  all.min_shared_landmarks = 1;
  all.min_shared_ratio = 0.0;
  std::lock_guard<std::mutex> lock(scheduler_mutex_);
  return scheduler_.graph().candidates(all);
}

}  // namespace cblox
