#pragma once

// Map maintenance, the mapper's second thread: keyframes anchor new subvolumes or join the
// active one, keyframe pose batches move subvolumes (no voxel is touched), and the fusion
// scheduler asks the tracker for conditional covariances of covisible subvolume pairs and
// hands the pairs it accepts to the fusion/export worker.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <unordered_set>
#include <utility>
#include <vector>

#include "core/geometry/se3.h"
#include "core/maintenance/fusion_scheduler.h"
#include "core/mapping/fusion_export_worker.h"
#include "core/mapping/mapper_config.h"
#include "core/mapping/mapper_problems.h"
#include "core/submap/submap_collection.h"
#include "core/submap/submap_creation_policy.h"

namespace cblox {

/// Settings of map maintenance (from MapperConfig). Plain value type.
struct MapMaintenanceConfig {
  FusionSchedulerConfig scheduler;
  /// Keyframes, pose batches and replies waiting (oldest dropped, counted), >= 1.
  size_t queue_capacity = 256;
  MaintenanceClock clock = MaintenanceClock::kSteady;
  /// The input clock's restart rule (MapperConfig::restart_after_backwards_s).
  double restart_after_backwards_s = 2.0;
};

/// Thread-safety: every public member function is thread-safe unless noted. The creation
/// policy is shared with the integrator thread under `*policy_mutex` (held across
/// SubmapCreationPolicy::onKeyframe + SubmapCollection::createSubmap, so no frame slips into
/// the old subvolume after a jump). Lock order: policy mutex -> collection; the queue mutex
/// and the scheduler mutex are leaves.
class MapMaintenance {
 public:
  /// Sends a covariance request (cblox-mapper: CBLOX_COV_REQUEST); called on the maintenance
  /// thread, must not block for long.
  using CovarianceRequester = std::function<void(const FusionCovarianceRequest&)>;
  /// Counts (and logs, rate-limited) `n` problems of a kind.
  using ProblemSink = std::function<void(InputProblem, const std::string&, uint64_t n)>;
  using LogSink = std::function<void(const std::string&)>;

  /// `collection`, `policy`, `policy_mutex` and `worker` must outlive it.
  MapMaintenance(MapMaintenanceConfig config, SubmapCollection* collection,
                 SubmapCreationPolicy* policy, std::mutex* policy_mutex,
                 FusionExportWorker* worker, ProblemSink problems, LogSink log);
  /// Calls stop().
  ~MapMaintenance();
  MapMaintenance(const MapMaintenance&) = delete;
  MapMaintenance& operator=(const MapMaintenance&) = delete;

  /// Where covariance requests go; without one, no subvolume is fused. Before start().
  /// Not thread-safe.
  void setCovarianceRequester(CovarianceRequester requester);
  /// Called on the maintenance thread after a pose batch moved at least one subvolume (the
  /// mapper's planning map takes the new poses). Before start(). Not thread-safe.
  void setPosesMovedCallback(std::function<void()> callback);
  /// Starts the thread. Call once.
  void start();
  /// Applies the keyframes and pose batches still queued (so the map's frames are final;
  /// logged), then joins. Idempotent.
  void stop();

  /// A keyframe (T_G_K, the landmarks it observes), queued.
  void enqueueKeyframe(KeyframeId id, int64_t utime, const Transformationd& T_G_K,
                       std::vector<uint64_t> landmark_ids);
  /// Corrected keyframe poses T_G_K, queued.
  void enqueueBatch(std::vector<std::pair<KeyframeId, Transformationd>> T_G_K);
  /// The reply to a covariance request (one answer per pair, in order), queued.
  void enqueueReply(int64_t request_id, std::vector<FusionCovarianceAnswer> answers);
  /// Ground-truth mode: a keyframe the mapper synthesised at a frame, applied on the
  /// maintenance thread after what is queued; returns once it is applied (false, not
  /// applied, when maintenance is stopping). A synthesised id used before gets the next
  /// unused one. Not from the maintenance thread.
  bool applySynthesisedKeyframe(KeyframeId id, int64_t utime, const Transformationd& T_G_K);
  /// Asks the fusion scheduler for due pairs once more, after what is queued, with no input:
  /// on MaintenanceClock::kInput the only way a pair that became free after the last input
  /// (the last subvolume finished, a fusion done) is asked before the next input. The
  /// steady clock does this by itself every 0.25 s.
  void tick();
  /// The integrator started revisit submap `revisit`, anchored at the anchor keyframe of
  /// submap `home` (SubmapCreationPolicy::onFrameReference): makes it a subvolume of the
  /// fusion scheduler sharing home's anchor (FusionScheduler::addSubvolumeSharingAnchor) and
  /// logs it. Call with `*policy_mutex` held, right after SubmapCollection::createSubmap, so
  /// no keyframe joins it before the scheduler knows it.
  /// `reason`: the rule that started it (logged), kRevisitFrames or kRevisitAfterJump.
  void adoptRevisitSubmap(SubmapId revisit, SubmapId home, KeyframeId anchor,
                          SubmapCreationPolicy::Reason reason);
  /// The worker's result for an accepted pair (FusionExportWorker::FusionCallback).
  void onFusionResult(const FusionPair& pair, bool fused);
  /// An accepted depth frame or pose at `utime` (MaintenanceClock::kInput's time).
  void advanceInputClock(int64_t utime);
  /// Makes submaps restored from a saved map (loadMap) known as created ones are: their
  /// keyframe ids count as applied (a repeated id is a duplicate; a synthesised one gets the
  /// next unused id) and each is a subvolume of the fusion scheduler with its anchor
  /// keyframe; then `state` (the saved FusionScheduler state: covisibility landmark sets,
  /// back-offs of rejected pairs; empty for maps saved before manifest version 2) is restored
  /// (FusionScheduler::restoreState), so loaded subvolumes are fusion candidates as they were.
  /// Returns the number of state entries that name no loaded subvolume (ignored). Call with
  /// `*policy_mutex` held (as passed to the constructor), right after the load, before any
  /// keyframe is applied to the loaded map.
  size_t adoptLoadedSubmaps(const std::vector<std::shared_ptr<Submap>>& submaps,
                            const FusionSchedulerState& state);
  /// The fusion scheduler's state now (FusionScheduler::exportState), for a checkpoint or a
  /// save.
  FusionSchedulerState schedulerState() const;

  /// Nothing queued and nothing in hand.
  bool idle() const;
  uint64_t keyframesApplied() const { return keyframes_applied_.load(); }
  uint64_t keyframeBatches() const { return keyframe_batches_.load(); }
  uint64_t submapsMoved() const { return submaps_moved_.load(); }
  FusionSchedulerStats schedulerStats() const;
  /// Every covisibility edge (pairs sharing a landmark), strongest first.
  std::vector<CovisibilityCandidate> covisibilityEdges() const;

 private:
  struct Item {
    enum class Kind { kKeyframe, kSynthesisedKeyframe, kBatch, kCovarianceReply, kTick };
    Kind kind = Kind::kKeyframe;
    KeyframeId keyframe_id = 0;
    int64_t utime = 0;
    Transformationd T_G_K;
    std::vector<uint64_t> landmark_ids;
    std::vector<std::pair<KeyframeId, Transformationd>> batch;
    int64_t request_id = 0;
    std::vector<FusionCovarianceAnswer> answers;
    std::shared_ptr<std::promise<void>> applied;  // kSynthesisedKeyframe
  };
  void loop();
  // False when stopping (the item is not queued).
  bool enqueue(Item item);
  void apply(const Item& item);
  void applyKeyframe(KeyframeId id, int64_t utime, const Transformationd& T_G_K,
                     bool synthesised, std::span<const uint64_t> landmark_ids);
  void applyBatch(const std::vector<std::pair<KeyframeId, Transformationd>>& batch);
  void applyReply(const Item& item);
  // Same-anchor pairs go to the worker at once; then a covariance request, if one is due.
  void scheduleFusions();
  // Logs same-anchor pairs (FusionScheduler::takeSameAnchorPairs) and hands them to the worker.
  void submitSameAnchorPairs(const std::vector<FusionPair>& pairs);
  double seconds() const;

  const MapMaintenanceConfig config_;
  SubmapCollection* const collection_;
  SubmapCreationPolicy* const policy_;
  std::mutex* const policy_mutex_;
  FusionExportWorker* const worker_;
  const ProblemSink problems_;
  const LogSink log_;
  CovarianceRequester covariance_requester_;
  std::function<void()> poses_moved_;  // empty: none

  // Guarded by *policy_mutex_ (applyKeyframe).
  std::unordered_set<KeyframeId> keyframes_seen_;
  KeyframeId max_keyframe_seen_ = -1;

  mutable std::mutex queue_mutex_;  // guards the queue and the flags
  std::condition_variable queue_cv_;
  std::deque<Item> queue_;
  bool busy_ = false, stop_ = false, started_ = false, stopped_ = false;
  std::thread thread_;

  mutable std::mutex scheduler_mutex_;  // guards scheduler_ (a leaf)
  FusionScheduler scheduler_;
  const std::chrono::steady_clock::time_point start_time_ = std::chrono::steady_clock::now();
  std::mutex input_clock_mutex_;  // guards last_input_utime_ (a leaf)
  int64_t last_input_utime_ = INT64_MIN;
  std::atomic<int64_t> input_clock_us_{0};
  std::atomic<uint64_t> keyframes_applied_{0}, keyframe_batches_{0}, submaps_moved_{0};
};

}  // namespace cblox
