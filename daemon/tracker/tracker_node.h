#pragma once

// The tracker of cblox-tracker without LCM: decoded frames in, frame poses, keyframes and
// keyframe pose batches out through callbacks, with its own tracking thread around the sparse
// SLAM system of core/tracking. daemon/cblox_tracker.cc only converts LCM messages into
// these calls and the callbacks into messages.

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "core/common/checkpoint_config.h"
#include "core/common/in_tray.h"
#include "core/common/rate_limited_log.h"
#include "core/common/timing_window.h"
#include "core/geometry/se3.h"
#include "core/geometry/stereo_rig.h"
#include "core/tracking/keyframe_covariance_service.h"
#include "core/tracking/slam_system.h"
#include "core/vocabulary/binary_vocabulary.h"
#include "daemon/tracker/ground_truth_buffer.h"
#include "daemon/tracker/image_check.h"
#include "daemon/tracker/tracker_checkpoint_worker.h"
#include "daemon/tracker/tracker_input.h"
#include "daemon/tracker/tracker_resume.h"

namespace cblox {

/// Which frames the tracker takes.
enum class TrackerMode {
  kStereo,  ///< rectified stereo pairs (CBLOX_STEREO)
  kRgbd,    ///< depth with registered colour (CBLOX_DEPTH), ORB-SLAM2's RGB-D mode
};
const char* trackerModeName(TrackerMode mode);

/// Where the pose of the first keyframe (and so the tracker's frame G) comes from.
enum class InitialPose {
  kIdentity,     ///< G is the camera frame of the first keyframe
  kGroundTruth,  ///< G is the ground truth's frame: the first keyframe gets its pose there
};
const char* initialPoseName(InitialPose initial_pose);

/// Settings of a TrackerNode (the tracking part of config/tracker.yaml). Plain value type.
struct TrackerNodeConfig {
  TrackerMode mode = TrackerMode::kStereo;
  /// The sparse SLAM system (features, tracking, local mapping, loop closing).
  SlamSystemConfig slam;
  /// Niceness (0-19) of the local mapping and the loop closing threads (and of the global BA
  /// thread loop closing starts, which inherits it); the tracking thread keeps the process's.
  /// On two cores local and global BA can run beside tracking at once: at 10 they yield to it
  /// (the town's p95 frame 26-32 -> 22 ms on one core, BENCHMARKS.md). 0 = the same priority.
  int local_mapping_niceness = 10;
  int loop_closing_niceness = 10;
  /// The camera, fixed by configuration (a calibration file); absent: each frame's message
  /// carries it, and the first valid frame fixes it for the run.
  std::optional<RectifiedStereoCalibration> calibration;
  /// Features closer than this many baselines have trusted depth (ORB-SLAM2's ThDepth:
  /// 35-40), > 0.
  double close_depth_baselines = 40.0;
  /// RGB-D mode: the virtual stereo baseline, metres (> 0). ORB-SLAM2 configures bf = 40 px m
  /// for the TUM/7-Scenes cameras (fx ~ 520-585 px), i.e. 0.07-0.08 m.
  double rgbd_baseline_m = 0.08;
  InitialPose initial_pose = InitialPose::kIdentity;
  /// initial_pose ground_truth: how long a frame waits for its ground-truth pose, seconds
  /// (>= 0); without it the frame is published NOT_INITIALIZED.
  double ground_truth_wait_s = 1.0;
  /// A frame whose time stamp is this much older than the previous frame's means the source
  /// restarted (a log or the simulator run again): the tracker drops its map and starts a
  /// new one in the next map epoch, instead of rejecting every frame as out of order.
  /// Smaller steps back are rejected as out of order. Frame ids going back while time goes
  /// on (a capture process restarted on a live clock) continue the same map. 0 = never.
  double restart_after_backwards_s = 2.0;
  /// Frames waiting for the tracking thread, [1, 16]; when more arrive the oldest is dropped
  /// (counted).
  size_t queue_capacity = 4;
  /// True: the waiting frames are tracked in order, so after a stall (a loop correction or a
  /// global BA applied under the map's lock, another process on the core) the tracker
  /// catches up on every frame, at most queue_capacity frames late. False: the newest wins
  /// and the older waiting frames are dropped (the lowest latency; frames are lost in a stall).
  bool catch_up = true;
  /// Frames that cannot be tracked at all are published LOST without tracking them.
  ImageCheckConfig image_check;
  /// Tracking times kept for the median / p95 in status, >= 1.
  size_t timing_window = 200;
  /// Minimum interval between two log lines of the same problem kind, seconds (> 0).
  double log_interval_s = 10.0;
  /// The covariance service (CBLOX_COV_REQUEST -> CBLOX_COV_REPLY) for the mapper.
  KeyframeCovarianceServiceConfig covariance;
  /// Checkpoints of the sparse map (README "Tracker map format"): with a directory, the map
  /// is saved every period_s seconds and when the node stops, and the keyframe / landmark
  /// ids published are covered by the directory's id lease. Resume is the caller's
  /// (loadTrackerResume, then TrackerNode::resumeFrom).
  CheckpointConfig checkpoint;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

/// The SlamSystem thread-start hook of cblox-tracker: lowers the local mapping and the loop
/// closing threads to config.local_mapping_niceness / loop_closing_niceness; what fails goes
/// to `log` (the thread keeps running). cblox-bench-slam uses it too, to measure what runs.
SlamSystem::ThreadStartHook slamThreadPriorities(const TrackerNodeConfig& config,
                                                 std::function<void(const std::string&)> log);

/// The published state of a frame (frame_pose_t's tracking states).
enum class FramePoseState {
  kNotInitialized,
  kOk,
  kLost,
  kRelocalized,
  kLoopCorrected,
  kMapReset,  ///< the first pose of a new map (epoch) after the source restarted
};

/// What the tracker says about one frame (CBLOX_FRAME_POSE). Plain value type.
struct FramePoseReport {
  int64_t utime = 0;
  int64_t frame_id = 0;
  /// The map the pose is in: 0, then one more each time the source restarted.
  int32_t map_epoch = 0;
  FramePoseState state = FramePoseState::kNotInitialized;
  /// The pose jumped relative to the previous published pose: relocalized, loop corrected,
  /// or the first pose after frames without one.
  bool jump = false;
  /// The camera (rectified left / RGB-D) pose T_G_C; set for kOk, kRelocalized and
  /// kLoopCorrected.
  std::optional<Transformationd> T_G_C;
  /// The keyframe the frame was tracked against (TrackingResult::reference_keyframe), -1
  /// when there is no pose.
  int64_t reference_keyframe_id = -1;
  /// Why there is no pose (empty when there is one).
  std::string reason;
};

/// A snapshot of the tracker's counters since start. Plain value type.
struct TrackerStatus {
  uint64_t frames_received = 0;   ///< frames offered, bad ones included
  uint64_t frames_rejected = 0;   ///< sum of the rejection kinds
  uint64_t frames_dropped = 0;    ///< superseded in the queue (the tracker was behind)
  uint64_t frames_processed = 0;  ///< frames the tracking thread published a pose for
  uint64_t frames_tracked = 0;    ///< published with a pose (OK, RELOCALIZED, LOOP_CORRECTED)
  uint64_t frames_lost = 0;       ///< published LOST
  uint64_t frames_not_initialized = 0;
  uint64_t relocalizations = 0;  ///< frames published RELOCALIZED
  uint64_t loop_corrected_frames = 0;
  uint64_t keyframes = 0;        ///< CBLOX_KEYFRAME messages
  uint64_t pose_batches = 0;     ///< CBLOX_KEYFRAME_POSES messages
  uint64_t source_restarts = 0;  ///< time or frame ids went back (see restart_after_backwards_s)
  int32_t map_epoch = 0;         ///< the map in use: one more per restart with time going back
  uint64_t landmarks = 0;        ///< landmarks in the map now
  uint64_t loops_closed = 0;
  /// Loop candidates refused by the drift gate (a correction larger than it allows), and
  /// corrections whose essential graph failed to solve (the map keeps its group's move).
  uint64_t loops_rejected_drift = 0, essential_graphs_failed = 0;
  uint64_t local_bundle_adjustments = 0;
  /// Local BAs stopped early by a new keyframe (their progress is kept).
  uint64_t local_bundle_adjustments_interrupted = 0;
  /// CPU of the local mapping thread so far, milliseconds (all its steps; LocalMapperStats).
  double local_mapping_cpu_ms = 0.0;
  uint64_t global_bundle_adjustments = 0;
  /// Global BAs dropped because a newer loop or a move of the map made them stale.
  uint64_t global_bundle_adjustments_abandoned = 0;
  /// Covariance service: requests, pairs answered with a covariance / with an error, and
  /// the last linearization's build (map -> S) and last request's solve times, milliseconds.
  uint64_t covariance_requests = 0;
  uint64_t covariance_pairs_ok = 0;
  uint64_t covariance_pairs_failed = 0;
  /// Linearizations of the map, and requests answered from a kept one.
  uint64_t covariance_linearizations = 0, covariance_reused = 0;
  double covariance_build_ms = 0.0, covariance_solve_ms = 0.0;
  /// Tracking time of a frame (TrackingResult::time_ms) and the whole frame (features,
  /// stereo matching and tracking), milliseconds, over the last timing_window frames.
  double tracking_ms_median = 0.0, tracking_ms_p95 = 0.0;
  double frame_ms_median = 0.0, frame_ms_p95 = 0.0;
  /// Checkpoints of the sparse map: written, failed, the generation last committed (0: none),
  /// the last one's wall time; id lease writes; keyframes restored at start (0: a new map).
  uint64_t checkpoints_written = 0, checkpoint_failures = 0, checkpoint_generation = 0;
  double last_checkpoint_ms = 0.0;
  uint64_t id_lease_renewals = 0, id_lease_failures = 0;
  uint64_t resumed_keyframes = 0;
  std::array<uint64_t, kNumTrackerProblems> problems{};  ///< indexed by TrackerProblem
  /// "waiting for frames", "tracking", "lost: <why>", "not initialized: <why>".
  std::string state = "waiting for frames";
  uint64_t problem(TrackerProblem p) const { return problems[static_cast<size_t>(p)]; }
};

/// The tracker process's core: validates decoded frames, keeps a bounded in-tray (newest
/// wins), and runs the SlamSystem on its tracking thread.
///
/// Threads (owned; start() starts, stop() joins):
/// - Callers (the LCM thread of cblox-tracker, or a test) call onFrame(), onGroundTruth()
///   and reportProblem(). They validate, count and hand over; they never wait for tracking.
/// - The tracking thread takes the newest waiting frame, checks that its images can be
///   tracked at all (ImageCheckConfig), waits for its ground-truth pose while the map is not
///   started (initial_pose ground_truth), runs SlamSystem::trackStereo / trackRgbd and
///   reports the frame (Outputs::frame_pose). The SlamSystem is created on the first frame
///   (with the configured camera, or the one of that frame's message).
/// - The SlamSystem's local mapping and loop closing threads call Outputs::keyframe_poses.
///
/// Thread-safety: every public member function is thread-safe unless noted.
class TrackerNode {
 public:
  /// Where the results go. Each callback may be empty. frame_pose and keyframe run on the
  /// tracking thread, keyframe_poses on the SlamSystem's threads, log on any thread: they
  /// must be thread-safe with respect to each other (e.g. one publish mutex).
  struct Outputs {
    std::function<void(const FramePoseReport&)> frame_pose;
    std::function<void(const KeyframeInfo&)> keyframe;
    std::function<void(const KeyframePoseBatch&, PoseUpdateReason)> keyframe_poses;
    /// Covariance replies: on the covariance service's thread (or the caller's, for a
    /// request made before the map exists or dropped because the service was busy).
    std::function<void(const KeyframeCovarianceReply&)> covariance_reply;
    /// Human-readable lines (problems, loop closures); default: stderr.
    std::function<void(const std::string&)> log;
  };

  /// Throws std::invalid_argument with TrackerNodeConfig::validate()'s message. `vocabulary`
  /// may be null (no relocalization, no loop closing) and must outlive the node.
  TrackerNode(const TrackerNodeConfig& config, const BinaryVocabulary* vocabulary, Outputs outputs);
  /// Calls stop().
  ~TrackerNode();
  TrackerNode(const TrackerNode&) = delete;
  TrackerNode& operator=(const TrackerNode&) = delete;

  /// Continue a saved map (loadTrackerResume) instead of starting a new one: the map is
  /// restored when the camera is known (the first frame, or the configured calibration) and
  /// the tracker then relocalizes in it; published ids continue above the resume's floors.
  /// When the saved map's camera is not the one in use, or the map does not restore, a new
  /// map starts in the epoch after it (logged). Call before start().
  void resumeFrom(TrackerResume resume);
  /// Starts the tracking thread (and the checkpoint worker when configured). Call once.
  void start();
  /// The tracking thread finishes the frame in hand (waiting frames are dropped), then the
  /// SlamSystem stops (local mapping and loop closing finish what they hold; their last pose
  /// batches are still reported), then a last checkpoint is written when configured.
  /// Idempotent; not from a callback.
  void stop();

  /// A decoded frame arrived: checks its calibration against the one in use (or the
  /// configured one), its image size and its order (frame_id and utime must increase), then
  /// queues it. Returns false when it was rejected (counted and logged).
  bool onFrame(TrackerFrame frame);
  /// A ground-truth pose T_G_C of a frame (CBLOX_GT_POSE), used only with initial_pose
  /// ground_truth.
  void onGroundTruth(int64_t frame_id, int64_t utime, const Transformationd& T_G_C);
  /// A covariance request (CBLOX_COV_REQUEST): queued for the covariance service, which
  /// answers through Outputs::covariance_reply; before the map exists every pair fails at
  /// once ("the tracker has no map yet"), and so does every pair of a request about another
  /// map epoch than the one in use.
  void onCovarianceRequest(KeyframeCovarianceRequest request, int32_t map_epoch = 0);
  /// Counts and logs a problem found outside the node (e.g. a message that did not decode).
  /// A rejection kind also counts as a received frame.
  void reportProblem(TrackerProblem problem, const std::string& detail);

  TrackerStatus status() const;
  /// The map epoch of the map in use (see FramePoseReport::map_epoch). Thread-safe. Outputs
  /// called from the SLAM threads are in this epoch: the old map's threads are stopped before
  /// it changes.
  int32_t mapEpoch() const { return map_epoch_.load(); }
  /// Waits until no frame is waiting or in hand (or `timeout` passes); true when idle. Local
  /// mapping may still be busy. For tests.
  bool waitUntilIdle(std::chrono::milliseconds timeout) const;
  /// Waits until the node is idle and so is everything it started: local mapping, loop
  /// closing (with its global BA) and the covariance service, so that every output of the
  /// inputs given so far has been delivered and nothing more will come without new input.
  /// False when the tracking thread was not idle within `timeout` (the SLAM threads are
  /// waited for without a limit). Deterministic replay calls it after every input; call it
  /// while no other thread hands frames over.
  bool waitUntilSettled(std::chrono::milliseconds timeout) const;

  /// The map as it is now, for a checkpoint (std::nullopt before the map has a keyframe).
  /// Thread-safe (takes the map's shared lock briefly; features are shared, not copied).
  std::optional<TrackerMapState> mapForCheckpoint() const;
  /// Writes a checkpoint now (false: none configured, or it failed). For tests.
  bool checkpointNow();

  const TrackerNodeConfig& config() const { return config_; }

 private:
  // Tracking thread: restores the pending resume into the new `system` (camera `camera`).
  void restorePending(SlamSystem* system, const TrackingCamera& camera);
  // Tracking thread: extends the id lease over a keyframe about to be published.
  void coverIds(const KeyframeInfo& info);
  void trackingLoop();
  void processFrame(TrackerFrame& frame);
  // Tracking thread: the SlamSystem for the camera in use (created on first use).
  bool ensureSystem(const RectifiedStereoCalibration& calibration, std::string* error);
  // Tracking thread: stops and drops the SLAM system (and its covariance service) so that the
  // next frame starts a new map, in the next epoch.
  void startNewMap(const TrackerFrame& frame);
  // Tracking thread: publishes a frame without a pose (LOST, or NOT_INITIALIZED before the
  // map exists), counts `problem` and records the state.
  void reportUntracked(const TrackerFrame& frame, TrackerProblem problem,
                       const std::string& reason);
  void publish(FramePoseReport report);  // stamps the map epoch
  void count(TrackerProblem problem, const std::string& message);
  void setState(std::string state);
  void log(const std::string& line) const;

  const TrackerNodeConfig config_;
  const BinaryVocabulary* const vocabulary_;
  const Outputs outputs_;
  InTray<TrackerFrame> queue_;
  GroundTruthBuffer ground_truth_;
  RateLimitedLog problem_log_;
  TimingWindow tracking_ms_, frame_ms_;

  // Input checks (callers' threads).
  std::mutex input_mutex_;
  std::optional<RectifiedStereoCalibration> camera_;  // the calibration in use
  int64_t last_frame_id_ = INT64_MIN, last_utime_ = INT64_MIN;

  // The SLAM system: created and destroyed on the tracking thread / in stop(), read by
  // status(); system_mutex_ guards the pointer, not the system.
  mutable std::mutex system_mutex_;
  std::unique_ptr<SlamSystem> system_;
  // Created with the system (reads its map); stopped first, destroyed first.
  std::unique_ptr<KeyframeCovarianceService> covariance_;
  TrackingCamera tracking_camera_;  // of system_ (system_mutex_)
  // Persistence: the resume waiting for the camera (tracking thread after start), the id
  // lease (tracking thread), the checkpoint writer.
  std::optional<TrackerResume> resume_;
  std::unique_ptr<IdLeaseKeeper> id_lease_;
  std::unique_ptr<TrackerCheckpointWorker> checkpoints_;
  std::atomic<uint64_t> id_lease_failures_{0}, resumed_keyframes_{0};
  // Tracking thread only.
  bool pose_published_ = false;     // the last published frame had a pose
  bool map_started_ = false;        // the tracker has initialised its map
  bool map_reset_pending_ = false;  // the next tracked pose is the new map's first (kMapReset)
  std::atomic<int32_t> map_epoch_{0};

  std::atomic<uint64_t> frames_received_{0}, frames_processed_{0}, frames_tracked_{0},
      frames_lost_{0}, frames_not_initialized_{0}, relocalizations_{0}, loop_corrected_frames_{0},
      keyframes_{0}, pose_batches_{0}, source_restarts_{0};
  std::array<std::atomic<uint64_t>, kNumTrackerProblems> problems_{};
  mutable std::mutex state_mutex_;
  std::string state_ = "waiting for frames";

  std::atomic<bool> stop_{false}, busy_{false};
  mutable std::mutex idle_mutex_;  // with idle_cv_: the tracking thread went idle
  mutable std::condition_variable idle_cv_;
  bool started_ = false, stopped_ = false;
  std::mutex lifecycle_mutex_;
  std::thread tracking_thread_;
};

}  // namespace cblox
