#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/features/scale_pyramid.h"
#include "core/optimization/bundle_adjustment.h"
#include "core/optimization/pose_graph_optimizer.h"
#include "core/tracking/keyframe_work_queue.h"
#include "core/tracking/local_mapper.h"
#include "core/tracking/sparse_map.h"
#include "core/tracking/tracking_camera.h"
#include "core/vocabulary/keyframe_database.h"

namespace cblox {

/// Settings of loop closing (ORB-SLAM2's LoopClosing, SE(3) for stereo / RGB-D).
struct LoopCloserConfig {
  /// No loop is searched until the map has this many keyframes, nor within this many
  /// keyframes of the last loop (ORB-SLAM2: 10).
  int min_keyframes_between_loops = 10;
  /// A candidate must be consistent (its covisibility group overlapping the previous
  /// keyframes' candidate groups) over this many consecutive keyframes (ORB-SLAM2: 3).
  int consistency_threshold = 3;
  /// Geometric verification: BoW matches per candidate (20); RANSAC iterations of the
  /// 3D-3D alignment (300) and the inliers it needs (20); matches after projecting the
  /// candidate's covisible landmarks at the verified pose (10 px window, descriptor distance
  /// <= 50) that remain inliers of a pose optimised on all of them (40).
  int min_bow_matches = 20;
  int ransac_iterations = 300;
  int min_ransac_inliers = 20;
  int min_projection_matches = 40;
  /// Drift gate (not in ORB-SLAM2): a verified loop is rejected when it would move the query
  /// keyframe by more than max_drift_m + max_drift_ratio * (path travelled along the
  /// keyframes from the candidate to the query). Places that repeat exactly (a street
  /// crossing every block, identical shelves) pass appearance and geometry checks with the
  /// wrong place; stereo odometry drifts by a few percent of the path, never by the whole
  /// distance between two look-alike places. Defaults 1 m and 0.1 (10 %).
  double max_drift_m = 1.0;
  double max_drift_ratio = 0.1;
  /// Essential graph: covisibility edges of at least this weight (100).
  int essential_graph_min_weight = 100;
  PoseGraphConfig pose_graph;
  /// Global BA after each loop correction (on this thread, the map usable meanwhile).
  bool global_bundle_adjustment = true;
  BundleAdjustmentConfig global_ba = globalBundleAdjustmentConfig();
  /// Random seed of RANSAC (deterministic runs).
  uint32_t seed = 1;

  std::string validate() const;
};

/// What one loop closure did.
struct LoopClosureEvent {
  KeyframeId query = 0;        ///< the new keyframe that closed the loop
  KeyframeId candidate = 0;    ///< the old keyframe it matched
  int inliers = 0;             ///< matches after verification
  double correction_m = 0.0;   ///< how far the query keyframe moved, metres
  double correction_ms = 0.0;  ///< time of the correction (pose graph included)
  /// Of correction_ms, the time the map's exclusive lock was held (tracking waits for it).
  double locked_ms = 0.0;
  /// Of correction_ms, the essential graph's optimisation (without the lock), and its size.
  double graph_ms = 0.0;
  int graph_keyframes = 0;
  int graph_edges = 0;
};

struct LoopCloserStats {
  uint64_t keyframes_checked = 0;
  uint64_t candidates_detected = 0;  ///< consistent candidates reaching verification
  uint64_t loops_rejected = 0;       ///< failed geometric verification
  /// Candidates that passed appearance and geometry but failed the drift gate (counted
  /// within loops_rejected when no other candidate of the keyframe passed).
  uint64_t loops_rejected_drift = 0;
  uint64_t loops_closed = 0;
  /// Corrections whose essential graph could not be solved (invalid input): the query's
  /// group was corrected, the rest of the map left as it was.
  uint64_t essential_graphs_failed = 0;
  uint64_t global_bundle_adjustments = 0;
  /// Global BAs stopped by a newer loop or by stop(), or whose result was stale (the map
  /// was corrected meanwhile) and not applied.
  uint64_t global_bundle_adjustments_abandoned = 0;
  double last_correction_ms = 0.0;
  double last_global_ba_ms = 0.0;
};

/// Loop closing: place recognition of each processed keyframe against the keyframe database
/// (BoW, consistency over consecutive keyframes), geometric verification (BoW matches, 3D-3D
/// RANSAC on the stereo landmarks, pose optimisation, projection search), then correction:
/// the query keyframe's covisible group is moved, duplicate landmarks are fused, the
/// essential graph (spanning tree, strong covisibility and loop edges) is optimised, every
/// landmark follows its reference keyframe, and a global BA refines everything.
///
/// Threads: insertKeyframe from the local mapping thread; run() on the loop closing thread.
/// The correction takes the map's exclusive lock twice (tracking waits then): to move the
/// query's covisible group, fuse the loop's landmarks and read the essential graph, then to
/// apply the graph's solution, which is computed between the two without the lock (ORB-SLAM2
/// holds it throughout: 0.7 s of tracking on the town's 680 keyframes). A keyframe made
/// meanwhile follows its parent, and local mapping starts no local BA meanwhile
/// (SparseMap::correctionPending: the keyframes it would hold fixed may be uncorrected ones).
/// Each of the two bumps SparseMap::changeIndex(), which makes an in-flight local BA discard
/// its result, and the tracker's frame in hand follows its reference keyframe. The global
/// BA after a correction runs on a thread of its own (ORB-SLAM2's RunGlobalBundleAdjustment),
/// so the loop closing thread goes on checking keyframes meanwhile (on 1000 keyframes a
/// global BA takes seconds); a newer loop correction aborts it first, and a result the map
/// has moved past (changeIndex) is not applied.
class LoopCloser {
 public:
  using LoopCallback = std::function<void(const LoopClosureEvent&)>;
  using PoseCallback = std::function<void(const KeyframePoseBatch&, bool global_ba)>;

  /// Throws std::invalid_argument for an invalid config or camera.
  LoopCloser(SparseMap* map, KeyframeDatabase* database, const TrackingCamera& camera,
             const ScalePyramid& pyramid, const LoopCloserConfig& config);

  void setLoopCallback(LoopCallback callback) { on_loop_ = std::move(callback); }
  /// Poses of keyframes a correction moved (global_ba false: the query's covisible group once
  /// it is moved, then every keyframe once the essential graph is applied) or after global BA
  /// (true: every keyframe).
  void setPoseCallback(PoseCallback callback) { on_poses_ = std::move(callback); }

  /// Queues a keyframe local mapping has finished. Thread-safe.
  void insertKeyframe(Keyframe* keyframe);
  /// Processes the oldest queued keyframe; false when there was none.
  bool processOne();
  void run();
  /// Stops the queue and aborts and joins a running global BA.
  void stop();
  /// Until no keyframe is queued or in hand and no global BA runs.
  void waitUntilIdle();
  ~LoopCloser();
  LoopCloserStats stats() const;

 private:
  struct Verified {
    Keyframe* candidate = nullptr;
    Transformationd T_C_G;  // corrected pose of the query keyframe
    // Per query feature: the loop landmark, or null. Held, not borrowed: between verify()
    // (shared lock) and correct() (exclusive lock) local mapping may retire one, and a raw
    // pointer would then dangle (a std::bad_weak_ptr abort on the town, end of lap 1).
    std::vector<std::shared_ptr<Landmark>> matches;
    int inliers = 0;
  };
  std::vector<Keyframe*> detect(Keyframe* keyframe);
  std::optional<Verified> verify(Keyframe* keyframe, const std::vector<Keyframe*>& candidates);
  /// The drift gate (LoopCloserConfig::max_drift_m / max_drift_ratio) for moving `keyframe`
  /// to the verified pose T_C_G. Needs the map's shared lock.
  bool plausibleCorrection(const Keyframe& keyframe, const Keyframe& candidate,
                           const Transformationd& T_C_G) const;
  void correct(Keyframe* keyframe, const Verified& loop);
  /// Aborts and joins the running global BA, if any.
  void abortGlobalBundleAdjustment();
  /// Starts globalBundleAdjustment on its own thread. None may be running: the caller aborts
  /// a running one before the loop correction that would make its result stale.
  void startGlobalBundleAdjustment(Keyframe* loop_keyframe);
  void globalBundleAdjustment(Keyframe* loop_keyframe);

  SparseMap* map_;
  KeyframeDatabase* database_;
  TrackingCamera camera_;
  ScalePyramid pyramid_;
  LoopCloserConfig config_;
  LoopCallback on_loop_;
  PoseCallback on_poses_;

  KeyframeWorkQueue queue_;

  // Loop-closing thread only.
  KeyframeId last_loop_keyframe_ = 0;
  struct ConsistentGroup {
    std::vector<KeyframeId> members;  // sorted
    int consistency = 0;
  };
  std::vector<ConsistentGroup> groups_;
  uint32_t rng_state_;

  mutable std::mutex stats_mutex_;
  LoopCloserStats stats_;

  // The global BA thread: started and joined by the loop closing thread (and stop()).
  std::mutex gba_mutex_;
  std::condition_variable gba_cv_;
  bool gba_running_ = false;  // guarded by gba_mutex_
  std::atomic<bool> abort_gba_{false};
  std::thread gba_thread_;
};

}  // namespace cblox
