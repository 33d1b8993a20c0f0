#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <vector>

#include <absl/container/flat_hash_set.h>

#include "core/geometry/se3.h"
#include "core/tsdf/layer_config.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox {

/// Id of a submap (subvolume), unique within its SubmapCollection, assigned 0, 1, 2, ... in
/// creation order and never reused.
using SubmapId = int64_t;
/// Id of a keyframe of the sparse SLAM map, as assigned by the tracker (keyframe_t).
using KeyframeId = int64_t;

/// True when the rotation quaternion and the translation are all finite. Thread-safe (pure).
bool isFinitePose(const Transformationd& T);

/// One subvolume of the map: a TSDF layer stored in the submap's own frame M, and the pose
/// T_G_M of that frame in the global frame G.
///
/// M is rigidly attached to the anchor keyframe K_a: T_G_M = T_G_K of that keyframe. When
/// the tracker corrects the keyframe's pose, only T_G_M changes (setT_G_M, usually through
/// SubmapCollection::updateKeyframePoses); no voxel is touched.
///
/// Life cycle: a submap is created *active* (the integrator thread integrates frames into
/// it) and becomes *finished* exactly once (finish()); a finished submap never becomes
/// active again.
///
/// Integration: a frame with camera pose T_G_C goes into the layer with
/// T_M_C = T_G_M^-1 * T_G_C (see T_M_C()); the mapper's integrator thread does
///
///     Submap::WriteLock lock = submap->lockForIntegration();
///     if (!lock) { /* finished meanwhile: fetch SubmapCollection::activeSubmap() again */ }
///     integrator.integrateDepthImage(submap->T_M_C(T_G_C), depth, camera, &color);
///
/// with an integrator constructed on &lock.layer() (ProjectiveTsdfIntegrator,
/// RayCastingIntegrator: one per active submap).
///
/// Thread safety (the rule the mapper follows; see also SubmapCollection):
/// - Immutable after construction, thread-safe: id(), anchorKeyframe(), creationTimeNs(),
///   layerConfig().
/// - Metadata (T_G_M, keyframe ids) is guarded by an internal leaf mutex: every metadata
///   accessor is thread-safe and returns values, never references.
/// - The layer of an ACTIVE submap is written only by the one thread that holds its layer
///   lock (lockForIntegration(), the integrator thread); any other thread that wants to read
///   an active submap's layer holds lockLayer() for as long as it reads.
/// - finish() takes the layer lock, so it waits for the frame in hand, and after it returns
///   no integrator writes the layer again (lockForIntegration() then returns an empty lock).
/// - The layer of a FINISHED submap belongs to the single fusion worker: only that thread
///   may modify it (fusion), and it may read it without a lock; other threads do not touch
///   a finished layer (they read numBlocks()/memoryBytes(), which are snapshots).
/// - numBlocks(), memoryBytes(), isActive(), isFinished() are atomic snapshots; the block and
///   memory figures are refreshed by the layer's writer (WriteLock release, fusion,
///   refreshStatistics()).
///
/// Change tracking: revision() is bumped whenever the layer may have changed: when a
/// non-empty WriteLock is released (an integrated frame), whenever mutableLayer() is handed
/// out (fusion writes through it; the bump happens before the write), and by the restoring
/// constructor (a restored layer is revision 1, a new empty one 0). Metadata changes (T_G_M,
/// keyframes) do not bump it. A reader that records revision() BEFORE copying the layer (a
/// checkpoint) knows the layer is unchanged since its copy while revision() still returns the
/// recorded value: an active layer is copied under lockLayer() and the WriteLock bumps before
/// it releases the lock; a finished layer is written only by the fusion worker, which is also
/// the thread that copies it, after taking mutableLayer() (and so after the bump).
/// Lock order: layer lock -> SubmapCollection mutex -> submap metadata mutex.
class Submap {
 public:
  /// Exclusive write access to an active submap's layer (one integrated frame). Empty (false)
  /// when the submap was already finished. Releasing it refreshes numBlocks()/memoryBytes()
  /// and bumps revision().
  /// Movable, not copyable; used by one thread.
  class WriteLock {
   public:
    WriteLock() = default;
    WriteLock(WriteLock&& other) noexcept = default;
    WriteLock& operator=(WriteLock&& other) noexcept;
    WriteLock(const WriteLock&) = delete;
    WriteLock& operator=(const WriteLock&) = delete;
    ~WriteLock();

    /// True when the lock is held (the submap is active and the layer may be written).
    explicit operator bool() const { return lock_.owns_lock(); }
    /// The layer. Precondition: the lock is held.
    TsdfLayer& layer() const { return submap_->layer_; }
    /// Releases the lock early (refreshing the statistics); no-op when empty.
    void unlock();

   private:
    friend class Submap;
    WriteLock(Submap* submap, std::unique_lock<std::mutex> lock)
        : submap_(submap), lock_(std::move(lock)) {}
    Submap* submap_ = nullptr;
    std::unique_lock<std::mutex> lock_;
  };

  /// A new, active, empty submap. The anchor keyframe is recorded as its first keyframe.
  /// Throws std::invalid_argument when the layer config is invalid or T_G_M is not finite.
  Submap(SubmapId id, const LayerConfig& layer_config, const Transformationd& T_G_M,
         KeyframeId anchor_keyframe, int64_t creation_time_ns);
  /// A new, active submap that takes over an existing `layer` (restoring a saved map; see
  /// SubmapCollection::restoreSubmap); layerConfig() is layer.config(). The anchor keyframe is
  /// recorded as its first keyframe, the statistics are refreshed and revision() is 1. Throws
  /// std::invalid_argument when T_G_M is not finite.
  Submap(SubmapId id, TsdfLayer layer, const Transformationd& T_G_M, KeyframeId anchor_keyframe,
         int64_t creation_time_ns);

  Submap(const Submap&) = delete;
  Submap& operator=(const Submap&) = delete;

  /// Thread-safe (immutable).
  SubmapId id() const { return id_; }
  /// The keyframe whose pose is T_G_M. Thread-safe (immutable).
  KeyframeId anchorKeyframe() const { return anchor_keyframe_; }
  /// Creation time as given by the creator (the mapper uses the anchor keyframe's capture
  /// time), nanoseconds. Thread-safe (immutable).
  int64_t creationTimeNs() const { return creation_time_ns_; }
  /// Thread-safe (immutable).
  const LayerConfig& layerConfig() const { return layer_config_; }

  /// Pose of the submap frame M in G, by value. Thread-safe.
  Transformationd T_G_M() const;
  /// Moves the submap frame; no voxel is touched. Returns false (and changes nothing) when
  /// T_G_M is not finite. Thread-safe.
  bool setT_G_M(const Transformationd& T_G_M);
  /// Camera pose in the submap frame for integration: T_M_C = T_G_M^-1 * T_G_C, composed in
  /// double and rounded to float once. Thread-safe.
  Transformation T_M_C(const Transformationd& T_G_C) const;

  /// Records that keyframe `id` contributed frames to this submap. Returns false when it
  /// was already recorded. Thread-safe.
  bool addKeyframe(KeyframeId id);
  /// Thread-safe.
  bool hasKeyframe(KeyframeId id) const;
  /// Number of distinct keyframes recorded (the anchor included). Thread-safe.
  size_t numKeyframes() const;
  /// The recorded keyframe ids, sorted ascending. Thread-safe.
  std::vector<KeyframeId> keyframeIds() const;

  /// Thread-safe (atomic).
  bool isActive() const { return !finished_.load(std::memory_order_acquire); }
  /// Thread-safe (atomic).
  bool isFinished() const { return finished_.load(std::memory_order_acquire); }
  /// Marks the submap finished: takes the layer lock (waits for a frame being integrated),
  /// refreshes the statistics and releases it; from then on the layer belongs to the fusion
  /// worker. Idempotent. Thread-safe; must not be called by a thread that holds this
  /// submap's layer lock (it would deadlock).
  void finish();

  /// Write access for the integrator thread; blocks while another thread holds the layer
  /// lock. Returns an empty lock when the submap is finished. Thread-safe.
  WriteLock lockForIntegration();
  /// The layer lock, for threads other than the integrator that read an ACTIVE submap's
  /// layer (e.g. exporting it); blocks integration while held. Not needed for finished
  /// submaps. Thread-safe.
  std::unique_lock<std::mutex> lockLayer() const { return std::unique_lock(layer_mutex_); }

  /// Read access to the layer. Allowed on the fusion worker for a finished submap, or while
  /// holding lockLayer() / a WriteLock, or when no other thread uses the submap (tests,
  /// single-threaded tools). Not synchronised by itself.
  const TsdfLayer& layer() const { return layer_; }
  /// Write access for the owner of a FINISHED submap (the fusion worker), or when no other
  /// thread uses the submap. Writers call refreshStatistics() when done. Bumps revision() (the
  /// caller may write through the pointer). Not synchronised (the bump itself is atomic).
  TsdfLayer* mutableLayer() {
    revision_.fetch_add(1, std::memory_order_acq_rel);
    return &layer_;
  }

  /// How often the layer may have changed (see "Change tracking" above): equal values mean
  /// an unchanged layer. Thread-safe (atomic).
  uint64_t revision() const { return revision_.load(std::memory_order_acquire); }

  /// Allocated blocks as of the last refresh. Thread-safe (atomic snapshot).
  size_t numBlocks() const { return num_blocks_.load(std::memory_order_relaxed); }
  /// Bytes of the layer (TsdfLayer::memoryBytes) as of the last refresh. Thread-safe.
  size_t memoryBytes() const { return memory_bytes_.load(std::memory_order_relaxed); }
  /// Recomputes numBlocks()/memoryBytes() from the layer (O(blocks)). Called by the layer's
  /// current writer only (same rule as mutableLayer()).
  void refreshStatistics();

 private:
  const SubmapId id_;
  const LayerConfig layer_config_;
  const KeyframeId anchor_keyframe_;
  const int64_t creation_time_ns_;

  mutable std::mutex meta_mutex_;  // leaf lock: guards T_G_M_ and keyframe_ids_
  Transformationd T_G_M_;
  absl::flat_hash_set<KeyframeId> keyframe_ids_;

  mutable std::mutex layer_mutex_;  // the layer lock (active submaps)
  std::atomic<bool> finished_{false};
  TsdfLayer layer_;
  std::atomic<size_t> num_blocks_{0};
  std::atomic<size_t> memory_bytes_{0};
  std::atomic<uint64_t> revision_{0};
};

}  // namespace cblox
