#pragma once

// The dense mapper of cblox-mapper without LCM: a SubmapCollection fed with depth frames,
// frame poses, keyframes and keyframe pose batches through method calls, with its own
// threads. daemon/cblox_mapper.cc only converts LCM messages into these calls.

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <unordered_set>
#include <utility>
#include <vector>

#include "core/common/in_tray.h"
#include "core/common/rate_limited_log.h"
#include "core/common/timing_window.h"
#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"
#include "core/integrator/integrator_config.h"
#include "core/integrator/make_integrator.h"
#include "core/maintenance/fusion_scheduler.h"
#include "core/mapping/depth_frame.h"
#include "core/mapping/frame_integration.h"
#include "core/mapping/fusion_export_worker.h"
#include "core/mapping/map_export.h"
#include "core/mapping/map_maintenance.h"
#include "core/mapping/mapper_command.h"
#include "core/mapping/mapper_config.h"
#include "core/mapping/mapper_problems.h"
#include "core/mapping/active_field_refresher.h"
#include "core/mapping/mesh_streamer.h"
#include "core/mapping/planning_map.h"
#include "core/mapping/pose_buffer.h"
#include "core/mesh/mesh_integrator.h"
#include "core/persistence/map_checkpointer.h"
#include "core/submap/submap_collection.h"
#include "core/submap/submap_creation_policy.h"
#include "core/submap/submap_fusion.h"
#include "core/tsdf/layer_config.h"

namespace cblox {

/// A snapshot of the mapper's state and counters since start. Plain value type.
struct MapperStatus {
  size_t num_submaps = 0;
  int64_t active_submap_id = -1;
  size_t num_blocks = 0;
  size_t memory_bytes = 0;  ///< subvolumes and distance fields
  uint64_t frames_received = 0;  ///< depth frames offered (incl. undecodable ones)
  uint64_t frames_integrated = 0;
  uint64_t frames_cut_by_budget = 0;  ///< integrated, but the time budget cut them short
  uint64_t frames_dropped = 0;        ///< superseded by a newer frame (newest wins) or queue full
  uint64_t frames_rejected = 0;       ///< sum of the frame problem kinds
  uint64_t frames_pending = 0;        ///< waiting for their pose now
  uint64_t poses_received = 0;
  uint64_t keyframes_applied = 0;  ///< keyframes that anchored a submap or joined one
  uint64_t keyframe_batches = 0;   ///< pose batches applied
  uint64_t submaps_moved = 0;      ///< (batch entry, anchored submap) pose updates
  uint64_t source_restarts = 0;    ///< depth or pose time stamps went back (new stream)
  uint64_t exports_done = 0;
  uint64_t exports_failed = 0;
  uint64_t checkpoints_written = 0;   ///< periodic checkpoints committed (checkpoint.dir)
  uint64_t checkpoint_failures = 0;   ///< periodic checkpoints that failed (map unchanged)
  float last_checkpoint_ms = 0.0f;    ///< wall time of the last committed checkpoint; 0: none
  uint64_t checkpoint_generation = 0;  ///< generation of the last committed checkpoint; 0: none
  int64_t last_checkpoint_utime = 0;   ///< when it committed, us since the Unix epoch; 0: none
  /// Map maintenance (FusionSchedulerStats): candidate pairs, pairs whose covariance was
  /// requested, accepted for fusion, rejected by q, answered with an error; fusions done and
  /// failed; requests timed out.
  FusionSchedulerStats fusion;
  float integration_ms_last = 0.0f;
  float integration_ms_median = 0.0f;
  float integration_ms_p99 = 0.0f;
  /// Age of integrated frames when their integration began (received -> start), ms.
  float frame_age_ms_median = 0.0f;
  float frame_age_ms_p99 = 0.0f;
  size_t memory_cap_bytes = 0;  ///< memory.cap_mb in bytes; 0 = no cap
  /// The memory cap's stage and what it did (memory_cap.h).
  MemoryCapCounters memory_cap;
  /// The planning map's fields (all zero when it is off); memory_bytes includes its bytes.
  PlanningMapStats planning;
  /// The planning map's refreshes that updated a field (on the worker), ms.
  float esdf_ms_median = 0.0f;
  float esdf_ms_p99 = 0.0f;
  /// The mesh stream's counters (all zero without one: setMeshStreamSinks).
  MeshStreamStats mesh_stream;
  std::array<uint64_t, kNumInputProblems> problems{};  ///< indexed by InputProblem
  uint64_t problem(InputProblem p) const { return problems[static_cast<size_t>(p)]; }
};

/// The dense mapper: integrates depth frames into the active subvolume of a SubmapCollection,
/// keeps subvolume frames in step with keyframe pose updates, and exports meshes.
///
/// Threads (all owned; started by start(), joined by stop()):
/// - Callers (the LCM thread in cblox-mapper, or a test) call the on*() inputs. They only
///   validate, count, and hand the input over: depth frames to the bounded InTray
///   in-tray (newest wins), poses to the PoseBuffer, keyframes and pose batches to the
///   maintenance queue, export, save_map and load_map commands to the worker queue. They never block on the map.
/// - Integrator thread (FrameIntegration, frame_integration.h): takes the newest pending
///   frame whose pose the PoseBuffer can give (waiting up to max_pose_wait_s for a pose that
///   is not there yet; frames it can never serve are rejected and counted by reason), applies
///   the creation policy (ground-truth mode: synthesises keyframes, which map maintenance
///   applies while the frame waits), and integrates into the active submap under
///   Submap::lockForIntegration() with T_M_D = T_G_M^-1 * T_G_B * T_B_D.
/// - Maintenance thread (MapMaintenance, map_maintenance.h): applies keyframes
///   (SubmapCreationPolicy::onKeyframe -> SubmapCollection::createSubmap, or Submap::addKeyframe)
///   and keyframe pose batches (SubmapCollection::updateKeyframePoses: frames move, no voxel is
///   touched). Map maintenance (FusionScheduler): each keyframe's landmark ids go into the
///   subvolume covisibility graph; after each keyframe, pose batch or reply (and every 0.25 s) it
///   asks the covariance requester for candidate pairs; replies (onCovarianceReply) come back
///   through its queue and pairs with q >= q_min go to the worker's fusion queue.
/// - Fusion/export worker thread (FusionExportWorker), at low priority (nice worker_niceness,
///   SCHED_IDLE): the single owner of FINISHED submap layers (SubmapCollection's rule); runs
///   commands first (exports, save_map, load_map), then fusions: the newer subvolume of a pair is fused into the older
///   (fuseSubmaps: trilinear, its keyframes join the older, so pose batches naming them stay known)
///   and removed from the collection. Both are finished (the active subvolume is never fused); only
///   the worker reads finished layers, so no reader sees a half-fused subvolume. It holds the
///   ACTIVE submap's layer lock only while copying that layer (a block memcpy), never while fusing,
///   meshing or writing, so an export delays integration by the copy. With checkpoint.dir and
///   checkpoint.period_s set, it also writes a checkpoint every period_s (its periodic task,
///   MapCheckpointer: only new and changed subvolumes, then the manifest), never on the
///   integrator thread; resumeFromCheckpoint() loads the last one at start. It also refreshes
///   the planning map's distance fields (planning_map.h): the finished subvolumes' every
///   planning.refresh_period_s and after each fusion, all after a load.
///
/// Shared state and its guards: the SubmapCollection and Submaps are thread-safe by their own rule;
/// the creation policy (not thread-safe) is guarded by policy_mutex_, which the integrator holds
/// only around onFramePose() and the keyframe path holds across onKeyframe() + createSubmap() (so
/// no frame slips into the old submap after a jump; the integrator never holds it while holding a
/// layer lock). Counters are atomics; the timing window (TimingWindow) has its own mutex. Lock
/// order: policy_mutex_ -> layer lock -> collection mutex -> submap metadata mutex;
/// depth_order_mutex_ -> pose_order_mutex_ (a restarted depth stream clears the poses); the InTray's and
/// PoseBuffer's mutexes and those of MapMaintenance and FusionExportWorker (their queues, the
/// FusionScheduler; never held while calling out) are leaves.
///
/// Thread-safety: every public member function is thread-safe unless noted.
class Mapper {
 public:
  using ReplyCallback = std::function<void(const MapperReply&)>;
  using LogSink = std::function<void(const std::string&)>;
  /// Sends a covariance request (cblox-mapper: CBLOX_COV_REQUEST). Called on the
  /// maintenance thread; must not block for long.
  using CovarianceRequester = std::function<void(const FusionCovarianceRequest&)>;

  /// Throws std::invalid_argument with MapperConfig::validate()'s message. `log` receives
  /// human-readable lines (default: stderr); it may be called from any of the threads.
  explicit Mapper(const MapperConfig& config, LogSink log = nullptr);
  /// Calls stop().
  ~Mapper();
  Mapper(const Mapper&) = delete;
  Mapper& operator=(const Mapper&) = delete;

  /// Where covariance requests go (tracker mode). Without one, no request is made and no
  /// subvolume is fused. Call before start(). Not thread-safe.
  void setCovarianceRequester(CovarianceRequester requester);
  /// Where the incremental mesh stream goes (cblox-mapper: CBLOX_MESH_UPDATE and
  /// CBLOX_SUBVOLUMES): with config().mesh_stream.enabled, a MeshStreamer (mesh_streamer.h)
  /// runs every mesh_stream.period_s on the fusion/export worker and calls the sinks there;
  /// the command mesh_refresh asks it for a full refresh. Without this call (or with the
  /// stream disabled) there is no stream and mesh_refresh is refused. Call before start(), at
  /// most once. Not thread-safe.
  void setMeshStreamSinks(MeshStreamer::UpdateSink on_update,
                          MeshStreamer::SubvolumeSink on_subvolumes);

  /// Creates the output directory and starts the threads. Returns false with a message when
  /// the output directory cannot be created (nothing started). Call once. Thread-safe.
  bool start(std::string* error);
  /// Stops the threads: the integrator finishes the frame in hand, the worker the export in
  /// hand (queued commands are answered "mapper stopping"), the maintenance thread applies
  /// the keyframes and pose batches still queued (logged); then joins them. Idempotent.
  /// Thread-safe (must not be called from a reply callback).
  void stop();

  /// A depth frame arrived. Validates it (sizes, intrinsics, time order) and puts it into the
  /// in-tray; returns false when it was rejected here (counted and logged). Thread-safe.
  bool onDepthFrame(DepthFrame frame);
  /// A frame pose arrived (ground truth: tracking_ok, no jump). Returns false when it was
  /// rejected (invalid, duplicate or out-of-order time stamp). Thread-safe.
  bool onFramePose(const TimedPose& pose);
  /// A new keyframe (tracker mode; in ground-truth mode the mapper makes its own, but this is
  /// accepted too). Queued for the maintenance thread; false when rejected at once
  /// (non-finite pose). Thread-safe.
  /// `landmark_ids`: the landmarks the keyframe observes (the covisibility graph's input).
  bool onKeyframe(KeyframeId id, int64_t utime, const Transformationd& T_G_K,
                  std::vector<uint64_t> landmark_ids = {});
  /// Corrected keyframe poses T_G_K (after BA / loop closure). Queued for the maintenance
  /// thread. Thread-safe.
  void onKeyframePoses(std::vector<std::pair<KeyframeId, Transformationd>> T_G_K);
  /// The reply to covariance request `request_id`: one answer per requested pair, in
  /// order. Queued for the maintenance thread. Thread-safe.
  void onCovarianceReply(int64_t request_id, std::vector<FusionCovarianceAnswer> answers);
  /// Map maintenance asks for due fusion pairs once more (MapMaintenance::tick): on the
  /// input clock (deterministic replay, the benches) after the last input, so pairs freed
  /// at the end are asked as the steady clock's tick would. Thread-safe.
  void maintenanceTick();
  /// A command. "status" and "mesh_refresh" (the next mesh stream period begins a full
  /// refresh; refused without a stream) are answered at once on the calling thread; "export_mesh" {path},
  /// "export_submap_meshes" {path}, "save_map" {path} and "load_map" {path} are queued for
  /// the worker and answered from it; anything else is answered at once with ok = false.
  /// Paths of exports and save_map are confined to the output directory (resolveOutputPath;
  /// refused at once otherwise); save_map writes a map directory there (saveMapToOutputDir,
  /// with statusCounters()). load_map's path is any map directory (loadMap below); it is
  /// refused at once while the map has a subvolume. `reply` is called exactly once (also
  /// when the mapper stops first). Thread-safe.
  void onCommand(const MapperCommand& command, ReplyCallback reply);
  /// Loads the saved map in `dir` (a map directory, core/persistence/map_store.h; not confined
  /// to the output directory: the operator's --load-map, or the load_map command) into the
  /// map, which must be empty, and makes its subvolumes known to map maintenance
  /// (MapMaintenance::adoptLoadedSubmaps). Refused, map unchanged, with a message in the
  /// reply: the map has a subvolume ("the map is not empty (N subvolumes): ..."), the saved
  /// layer geometry differs from config().layer (both named), or a file is missing or
  /// corrupt (named, loadMap's message). The reply's values: path, submaps, blocks, bytes,
  /// seconds, generation. Not restored (said in the message): the covisibility graph, so
  /// loaded subvolumes are no fusion candidates. Counters start from zero (the saved ones
  /// are not taken over). Thread-safe; holds the policy mutex during the load, so no
  /// keyframe creates a subvolume meanwhile (frames wait). Call before start() or on the
  /// worker (the load_map command).
  MapperReply loadMap(const std::string& dir);
  /// Resume at start (cblox-mapper, when no --load-map is given): when checkpoint.resume is
  /// set and checkpoint.dir holds a manifest, loads that checkpoint with loadMap() (same
  /// contract; the map must be empty). Returns std::nullopt when there is nothing to resume
  /// (resume off, no dir, or no manifest in it: a first run). Otherwise loadMap()'s reply,
  /// whose message is "resumed from <dir> generation N: S subvolumes (...)" on success; a
  /// failed reply (an unreadable checkpoint) is not to be ignored: cblox-mapper exits with
  /// status 2 and the message, the operator decides. Thread-safe; call before start().
  std::optional<MapperReply> resumeFromCheckpoint();
  /// The integer counters of status() by the names "status" replies with (frames_integrated,
  /// subvolumes_fused, ...; rejected_<kind> for every problem kind, zeros included): what
  /// save_map stores in the manifest. Thread-safe.
  std::map<std::string, int64_t> statusCounters() const;
  /// Counts and logs a problem found outside the mapper (e.g. a message that failed to
  /// decode in the LCM adapter). A depth-frame kind also counts as a received frame.
  /// Thread-safe.
  void reportProblem(InputProblem problem, const std::string& detail);

  /// A snapshot of the counters and the map's size. Thread-safe.
  MapperStatus status() const;
  /// The subvolume covisibility graph's edges (every pair sharing a landmark), strongest
  /// first, with the landmark set sizes: what the candidate bounds are applied to.
  /// Thread-safe.
  std::vector<CovisibilityCandidate> covisibilityEdges() const;
  /// Waits until no frame is pending or in hand and the maintenance and command queues are
  /// empty (or `timeout` passes); true when idle. For tests and orderly shutdown.
  /// Thread-safe.
  bool waitUntilIdle(std::chrono::milliseconds timeout) const;

  /// The map (its methods are thread-safe; see SubmapCollection for which layers may be
  /// touched from where). Thread-safe.
  const SubmapCollection& collection() const { return collection_; }
  /// The absolute output directory. Thread-safe (immutable after construction).
  const std::filesystem::path& outputDir() const { return output_dir_; }
  /// Thread-safe (immutable).
  const MapperConfig& config() const { return config_; }
  /// The planning map: distances, gradients and free/unknown space over the subvolumes,
  /// in G (planning_map.h; its queries are thread-safe). Null when config().planning is off.
  /// Every planning.refresh_period_s the finished subvolumes' fields follow the map on the
  /// worker, and the active subvolume's on a thread of its own at the integrator's priority.
  const PlanningMap* planningMap() const { return planning_.get(); }
  /// Makes the planning map follow the map now, the active subvolume included (on the
  /// worker, after the commands queued before; on the calling thread before start()), and
  /// waits for it: for callers that need
  /// the frames integrated so far in the answers. False when it did not happen within
  /// `timeout`, or the mapper is stopping. True at once when planning is off. Thread-safe.
  bool syncPlanningMap(std::chrono::milliseconds timeout);
  /// The map's epoch: a value that changes whenever the map is replaced (it is the wall
  /// time in us at construction, and moves to a new, larger value when a map is loaded or
  /// resumed); pose corrections do not change it. Compare for equality only. Thread-safe.
  int64_t mapEpoch() const { return map_epoch_.load(std::memory_order_acquire); }
  /// The newest tracked camera pose received (T_G_C with its time stamp), or nullopt.
  /// Thread-safe.
  std::optional<TimedPose> newestPose() const;
  /// The integrated frames' camera positions in G, oldest first, through the subvolumes'
  /// current poses (so a loop closure moves them as it moves the map); bounded and thinned
  /// (TrajectoryLog). Thread-safe.
  std::vector<Eigen::Vector3d> trajectoryG() const;

 private:
  MapperReply statusReply(const MapperCommand& command) const;
  // export_distance_grid / export_distance_slice: arguments checked here (a refusal goes
  // through `fail`, which answers through *reply), the file written on the worker after the
  // fields follow the map (the active subvolume's too; *reply moves there).
  void submitPlanningExport(const MapperCommand& command, ReplyCallback* reply,
                            const std::function<void(const std::string&)>& fail);
  static std::string notEmptyMessage(size_t num_submaps);

  // The periodic checkpoint (worker thread only): counts, logs a failure once per distinct
  // message, and when it recovers.
  void runCheckpoint();
  void count(InputProblem problem, const std::string& message, uint64_t n = 1);
  // True when `utime` is more than restart_after_backwards_s older than `newest_utime`.
  bool isRestart(int64_t newest_utime, int64_t utime) const;
  void log(const std::string& line) const;

  const MapperConfig config_;
  const LogSink log_sink_;
  const std::filesystem::path output_dir_;
  SubmapCollection collection_;
  RateLimitedLog problem_log_;

  // The creation policy, shared by the integrator (onFramePose) and map maintenance
  // (onKeyframe + createSubmap).
  std::mutex policy_mutex_;
  SubmapCreationPolicy policy_;

  std::atomic<uint64_t> frames_received_{0}, poses_received_{0}, source_restarts_{0};
  std::mutex pose_order_mutex_;  // serialises the restart decision of onFramePose
  std::array<std::atomic<uint64_t>, kNumInputProblems> problems_{};
  std::mutex depth_order_mutex_;
  int64_t last_depth_utime_ = INT64_MIN;

  std::atomic<int64_t> map_epoch_{0};
  bool started_ = false, stopped_ = false;
  std::mutex lifecycle_mutex_;

  // Periodic checkpoints: the checkpointer and the last failure's message are the worker's
  // (runCheckpoint); the counters are read by status().
  std::unique_ptr<MapCheckpointer> checkpointer_;  // null when checkpoints are off
  std::string last_checkpoint_error_;
  std::atomic<uint64_t> checkpoints_written_{0}, checkpoint_failures_{0};
  std::atomic<float> last_checkpoint_ms_{0.0f};
  // Set only after the manifest's rename and directory fsync (a committed checkpoint).
  std::atomic<uint64_t> checkpoint_generation_{0};
  std::atomic<int64_t> last_checkpoint_utime_{0};

  // The distance fields (null when config_.planning is off): refreshed by worker_ (every
  // planning.refresh_period_s, after fusions and loads), poses set by maintenance_, bytes
  // counted by integration_'s memory cap.
  std::unique_ptr<PlanningMap> planning_;
  std::unique_ptr<ActiveFieldRefresher> active_field_;  // with planning_: the active field
  // The incremental mesh stream (null without setMeshStreamSinks); ticks on worker_.
  std::unique_ptr<MeshStreamer> mesh_stream_;
  // Exports and accepted fusions, on its own low-priority thread; reports fusions to
  // maintenance_.
  FusionExportWorker worker_;
  // Keyframes, pose batches, covariance requests and replies, on its own thread; hands
  // accepted pairs to worker_ (constructed after it, destroyed before it).
  MapMaintenance maintenance_;
  // Depth frames, frame poses and the integrator thread; hands ground-truth keyframes to
  // maintenance_ (constructed after it, destroyed before it).
  FrameIntegration integration_;
};


}  // namespace cblox
