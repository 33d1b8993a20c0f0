#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "core/features/scale_pyramid.h"
#include "core/optimization/bundle_adjustment.h"
#include "core/tracking/disparity_correction.h"
#include "core/tracking/keyframe_sink.h"
#include "core/tracking/keyframe_triangulation.h"
#include "core/tracking/keyframe_work_queue.h"
#include "core/tracking/sparse_map.h"
#include "core/tracking/tracking_camera.h"

namespace cblox {

/// Settings of local mapping (ORB-SLAM2's LocalMapping).
struct LocalMapperConfig {
  /// Recent landmarks are retired when found in fewer than this fraction of the frames
  /// that should have seen them (0.25), or when they have at most min_observations
  /// observations (a stereo observation counting 2) two keyframes after their creation
  /// (ORB-SLAM2: 3 for stereo).
  double min_found_ratio = 0.25;
  int min_observations = 3;
  /// Duplicate fusion: best covisible keyframes searched (10 for stereo) and their best
  /// neighbours (5); projection window radius in pixels times the level scale (3).
  int fuse_neighbours = 10;
  int fuse_second_neighbours = 5;
  float fuse_radius = 3.0f;
  /// Local BA over the new keyframe and its covisible keyframes; the keyframes outside that
  /// see the window's landmarks are held fixed. At most this many covisible keyframes, the
  /// ones sharing the most landmarks with the new keyframe, are optimised (0 = all of them,
  /// as ORB-SLAM2); the others that see the window's landmarks are held fixed. 20 bounds
  /// the town's windows (40 covisible keyframes at the median with ORB-SLAM2's keyframe
  /// rule) and halves local mapping's CPU there at the same accuracy; indoors the windows
  /// are smaller than that (BENCHMARKS.md, "A bounded local BA window").
  int local_ba_max_keyframes = 20;
  BundleAdjustmentConfig bundle_adjustment;
  /// Keyframe culling: a keyframe whose close landmarks are >= this fraction seen by at
  /// least 3 other keyframes at the same or a finer scale is culled (ORB-SLAM2: 0.9).
  /// Off by default: the dense mapper anchors subvolumes on keyframes, and a culled
  /// keyframe's pose would no longer follow bundle adjustment.
  bool cull_keyframes = false;
  double redundant_ratio = 0.9;
  /// New landmarks triangulated between each keyframe and its best covisible keyframes
  /// (ORB-SLAM2's CreateNewMapPoints), judged by the recent-landmark culling above. Without
  /// them only the tracker's close stereo features become landmarks.
  bool create_new_landmarks = true;
  KeyframeTriangulationConfig triangulation;
  /// The stereo rig's disparity offset, estimated from local BA windows (with the landmarks
  /// and poses the BA solved) and corrected in new frames: see DisparityCorrection.
  DisparityCorrectionConfig disparity_correction;

  std::string validate() const;
};

/// Statistics (atomically readable from any thread).
struct LocalMapperStats {
  uint64_t keyframes_processed = 0;
  uint64_t landmarks_culled = 0;
  uint64_t landmarks_triangulated = 0;  ///< made by createNewLandmarks
  uint64_t landmarks_fused = 0;
  uint64_t keyframes_culled = 0;
  uint64_t bundle_adjustments = 0;
  uint64_t bundle_adjustments_aborted = 0;
  /// Stale after a loop correction, or not started while one was half done.
  uint64_t bundle_adjustments_discarded = 0;
  double last_ba_ms = 0.0;
  size_t largest_ba_window = 0;  ///< most keyframes optimised (not fixed) by one local BA
  /// The last local BA's size: keyframes optimised (the gauge, keyframe 0, counts as fixed
  /// when it is in the window) and held fixed, landmarks, observations.
  size_t last_ba_free_keyframes = 0;
  size_t last_ba_fixed_keyframes = 0;
  size_t last_ba_landmarks = 0;
  size_t last_ba_observations = 0;
  /// Disparity offset estimates: solves that gave one / gave none, their CPU seconds in all.
  uint64_t disparity_offset_estimates = 0;
  uint64_t disparity_offset_failures = 0;
  double disparity_offset_seconds = 0.0;
  /// CPU seconds of the local mapping thread per step, summed over every keyframe (the
  /// thread's own clock: time spent waiting for the map's lock is not counted).
  struct StepSeconds {
    double refresh = 0.0;            ///< the keyframe's landmarks and connections refreshed
    double cull_landmarks = 0.0;     ///< recent landmarks on probation checked
    double triangulate = 0.0;        ///< new landmarks with the covisible keyframes
    double fuse = 0.0;               ///< duplicate landmarks fused with the neighbours
    double bundle_adjustment = 0.0;  ///< local BA: the window read, solved, written back
    double cull_keyframes = 0.0;     ///< redundant keyframes (when culling is on)
    double total() const {
      return refresh + cull_landmarks + triangulate + fuse + bundle_adjustment + cull_keyframes;
    }
    StepSeconds& operator+=(const StepSeconds& o) {
      refresh += o.refresh;
      cull_landmarks += o.cull_landmarks;
      triangulate += o.triangulate;
      fuse += o.fuse;
      bundle_adjustment += o.bundle_adjustment;
      cull_keyframes += o.cull_keyframes;
      return *this;
    }
  };
  StepSeconds cpu_s;
};

/// ORB-SLAM2's local mapping for stereo / RGB-D: for every keyframe the tracker inserted,
/// refresh its landmarks' descriptors and viewing ranges, cull recent landmarks that do not
/// track well, triangulate new landmarks with the covisible keyframes, fuse duplicate
/// landmarks with them, run a local bundle adjustment and (optionally) cull redundant
/// keyframes, then hand the keyframe on (loop closing) and report the changed keyframe
/// poses.
///
/// Threads: insertKeyframe / acceptsKeyframes / queuedKeyframes / interruptBundleAdjustment
/// are called by the tracking thread; processOne() / run() by the local mapping thread (the
/// owner, e.g. the tracker process, creates that thread). Map access follows SparseMap's
/// rule: the BA is solved on a copy without any lock and written back under the exclusive
/// lock, so tracking is blocked only for the short edits.
class LocalMapper : public KeyframeSink {
 public:
  using KeyframeCallback = std::function<void(Keyframe*)>;
  using PoseCallback = std::function<void(const KeyframePoseBatch&)>;

  /// Throws std::invalid_argument for an invalid config or camera.
  LocalMapper(SparseMap* map, const TrackingCamera& camera, const ScalePyramid& pyramid,
              const LocalMapperConfig& config);

  // KeyframeSink (tracking thread).
  bool acceptsKeyframes() const override;
  size_t queuedKeyframes() const override;
  void insertKeyframe(Keyframe* keyframe) override;
  void interruptBundleAdjustment() override { abort_ba_ = true; }

  /// Called after each keyframe is processed (e.g. loop closing takes it), on the local
  /// mapping thread, without locks held.
  void setKeyframeCallback(KeyframeCallback callback) { on_keyframe_ = std::move(callback); }
  /// Called with the keyframes whose poses local BA changed, on the local mapping thread,
  /// without locks held.
  void setPoseCallback(PoseCallback callback) { on_poses_ = std::move(callback); }

  /// Processes the oldest queued keyframe; false when there was none. Local mapping thread.
  bool processOne();
  /// Processes keyframes until stop() (waits when idle). Local mapping thread.
  void run();
  /// Makes run() return after the keyframe in hand. Thread-safe.
  void stop();
  /// Waits until the queue is empty and no keyframe is in hand. Thread-safe.
  void waitUntilIdle();

  LocalMapperStats stats() const;
  DisparityCorrectionStats disparityCorrectionStats() const {
    return disparity_correction_.stats();
  }

 private:
  void processNewKeyframe(Keyframe* keyframe);
  void cullRecentLandmarks(Keyframe* keyframe);
  void triangulateNewLandmarks(Keyframe* keyframe);
  void fuseWithNeighbours(Keyframe* keyframe);
  void localBundleAdjustment(Keyframe* keyframe);
  /// One window's disparity offset from the local BA `problem` at its `solution`, with
  /// observation o made by feature observation_of[o]; the estimate goes to
  /// disparity_correction_.
  void estimateDisparityOffset(const BundleAdjustmentProblem& problem,
                               const BundleAdjustmentResult& solution,
                               const std::vector<std::pair<Keyframe*, uint32_t>>& observation_of);
  void cullKeyframes(Keyframe* keyframe);

  SparseMap* map_;
  TrackingCamera camera_;
  ScalePyramid pyramid_;
  LocalMapperConfig config_;
  KeyframeCallback on_keyframe_;
  PoseCallback on_poses_;

  KeyframeWorkQueue queue_;
  std::atomic<bool> abort_ba_{false};
  DisparityCorrection disparity_correction_;
  // Local BAs since the last disparity offset estimate (local mapping thread only); the
  // first local BA makes one.
  int local_bas_since_estimate_ = 1 << 30;

  std::list<std::shared_ptr<Landmark>> recent_landmarks_;  // local mapping thread only

  mutable std::mutex stats_mutex_;
  LocalMapperStats stats_;
};

}  // namespace cblox
