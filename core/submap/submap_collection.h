#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <absl/container/flat_hash_map.h>

#include "core/geometry/se3.h"
#include "core/submap/submap.h"
#include "core/tsdf/layer_config.h"

namespace cblox {

/// Settings of a SubmapCollection.
struct SubmapCollectionConfig {
  /// Geometry of every submap's layer (voxel size, block size). Default: 2 cm, 8^3 voxels.
  LayerConfig layer;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

/// What SubmapCollection::updateKeyframePoses did with one batch.
struct KeyframePoseUpdateResult {
  size_t submaps_moved = 0;      ///< submaps whose T_G_M was set (one per anchored submap)
  size_t keyframes_known = 0;    ///< batch entries whose keyframe is in some submap
  size_t keyframes_unknown = 0;  ///< batch entries whose keyframe no submap knows (ignored)
  size_t poses_invalid = 0;      ///< batch entries with a non-finite pose (ignored)
};

/// The submap's pose as seen at one instant (SubmapCollection::poseSnapshot).
struct SubmapPose {
  SubmapId id = 0;
  KeyframeId anchor_keyframe = 0;
  Transformationd T_G_M;
  bool active = false;  ///< it is the collection's active submap
};

/// The whole collection as seen at one instant (SubmapCollection::snapshot), e.g. for saving it.
struct SubmapCollectionState {
  std::vector<std::shared_ptr<Submap>> submaps;  ///< in creation (id) order
  std::shared_ptr<Submap> active;                ///< nullptr when there is no active submap
  SubmapId next_submap_id = 0;                   ///< the id the next createSubmap() assigns
};

/// The map: a collection of submaps Π = {π_p} with at most one active submap.
///
/// Thread safety (the mapper's threads; written down for issue 3.3):
/// - Every method is thread-safe. One internal mutex guards the container (ids, creation
///   order, the active submap, the anchor index); it is held only for short, bounded work and
///   never while waiting for a layer lock. Submap metadata (T_G_M, keyframe ids) has its own
///   leaf mutex inside Submap.
/// - Submaps are handed out as std::shared_ptr<Submap>: a reader keeps a submap alive
///   even when it is removed from the collection meanwhile.
/// - Poses are read by value (Submap::T_G_M(), poseSnapshot()); a batch of keyframe poses is
///   applied under the collection mutex, so poseSnapshot() never sees half a batch.
/// - Layers: only the ACTIVE submap's layer is written, by the integrator thread holding
///   Submap::lockForIntegration(). A FINISHED submap's layer is immutable for every thread
///   except the single fusion worker, which owns finished layers (fuses into them, reads
///   them for export) without locks. Another thread that must read an active layer (export
///   with include_active) holds Submap::lockLayer(), blocking integration meanwhile.
///   createSubmap()/removeSubmap()/finishActiveSubmap()
///   finish the previous active submap via Submap::finish(), which waits for the frame in
///   hand; they may therefore block for one frame's integration time, and must not be called
///   by a thread holding a layer lock.
/// - Typical threads: the integrator thread calls activeSubmap() and integrates; the
///   maintenance thread calls updateKeyframePoses(), createSubmap(), Submap::addKeyframe();
///   the low-priority fusion worker calls submaps()/getSubmap(), fuses finished submaps
///   (fuseSubmaps) and removes the fused source, and exports (projectCollection); status
///   reporting calls numBlocks(), memoryBytes(), poseSnapshot() from anywhere.
/// Lock order: Submap layer lock -> collection mutex -> Submap metadata mutex.
class SubmapCollection {
 public:
  /// Throws std::invalid_argument with SubmapCollectionConfig::validate()'s message.
  explicit SubmapCollection(const SubmapCollectionConfig& config);

  SubmapCollection(const SubmapCollection&) = delete;
  SubmapCollection& operator=(const SubmapCollection&) = delete;

  /// Thread-safe (immutable).
  const SubmapCollectionConfig& config() const { return config_; }

  /// Creates an empty submap with frame T_G_M attached to `anchor_keyframe` (recorded as its
  /// first keyframe), makes it the active one and finishes the previously active submap
  /// (waiting for a frame being integrated into it). Ids are 0, 1, 2, ... Throws
  /// std::invalid_argument when T_G_M is not finite (nothing changes then). Thread-safe.
  std::shared_ptr<Submap> createSubmap(const Transformationd& T_G_M, KeyframeId anchor_keyframe,
                                       int64_t creation_time_ns);

  /// Re-creates a saved submap (loading a map): takes over `layer` (its config must equal
  /// config().layer), keeps `id`, and sets the next id past it. When `finished` it is finished
  /// at once and the active submap does not change; otherwise it becomes the active one and
  /// the previously active submap is finished (as in createSubmap). Further keyframes are added
  /// with Submap::addKeyframe. Throws std::invalid_argument (and changes nothing) when `id` is
  /// below nextSubmapId() (ids only increase and are never reused), the layer config differs
  /// or T_G_M is not finite. Thread-safe; blocks like createSubmap when it finishes one.
  std::shared_ptr<Submap> restoreSubmap(SubmapId id, TsdfLayer layer, const Transformationd& T_G_M,
                                        KeyframeId anchor_keyframe, int64_t creation_time_ns,
                                        bool finished);
  /// The id the next createSubmap() assigns. Thread-safe.
  SubmapId nextSubmapId() const;
  /// Raises the next id to `next_id` (no change when it is already at least that), so that ids
  /// of saved submaps that were removed before saving are not reused after loading.
  /// Thread-safe.
  void reserveSubmapIds(SubmapId next_id);

  /// nullptr when no submap has this id. Thread-safe.
  std::shared_ptr<Submap> getSubmap(SubmapId id) const;
  /// The active submap, nullptr when there is none (before the first, after
  /// finishActiveSubmap() or removal of the active one). Thread-safe.
  std::shared_ptr<Submap> activeSubmap() const;
  /// Finishes the active submap (if any); afterwards there is none. Thread-safe.
  void finishActiveSubmap();
  /// Removes a submap from the collection (finishing it first when it is the active one);
  /// holders of its shared_ptr keep it alive. False when the id is unknown. Thread-safe.
  bool removeSubmap(SubmapId id);

  /// Ids in creation order. Thread-safe (a snapshot).
  std::vector<SubmapId> submapIds() const;
  /// Submaps in creation order. Thread-safe (a snapshot of the container; see the class
  /// comment for which layers the caller may touch).
  std::vector<std::shared_ptr<Submap>> submaps() const;
  /// Submaps, active submap and next id taken under one lock, so they are consistent with
  /// each other (the active submap is in the list). Thread-safe (see the class comment for
  /// which layers the caller may touch).
  SubmapCollectionState snapshot() const;
  /// Thread-safe.
  size_t size() const;
  /// Thread-safe.
  bool empty() const { return size() == 0; }

  /// Applies a batch of corrected keyframe poses T_G_K: every submap anchored to keyframe k
  /// gets T_G_M = T_G_K[k]. No voxel is touched. Entries are applied in order (for a
  /// repeated id the last valid pose wins). An entry whose keyframe is not recorded in any
  /// submap (neither anchor nor contributor) is ignored and counted as unknown; an entry with
  /// a non-finite pose is ignored and counted as invalid. submaps_moved counts each
  /// (entry, anchored submap) application. O(batch + submaps * batch) hash lookups.
  /// Thread-safe; the whole batch is applied atomically with respect to poseSnapshot().
  KeyframePoseUpdateResult updateKeyframePoses(
      const std::vector<std::pair<KeyframeId, Transformationd>>& T_G_K);

  /// Sum of Submap::numBlocks() (snapshots refreshed by the layers' writers). Thread-safe.
  size_t numBlocks() const;
  /// Sum of Submap::memoryBytes(). Thread-safe.
  size_t memoryBytes() const;
  /// Id, anchor, T_G_M and state of every submap in creation order, taken atomically with
  /// respect to updateKeyframePoses(). Thread-safe.
  std::vector<SubmapPose> poseSnapshot() const;
  /// The oldest (lowest id) submap that records `keyframe` (as anchor or contributor), as
  /// poseSnapshot() gives it; nullopt when none does. O(submaps) hash lookups. Thread-safe.
  std::optional<SubmapPose> oldestSubmapWithKeyframe(KeyframeId keyframe) const;

 private:
  // Finishes `previous` unless it is null (called without holding mutex_).
  static void finishOutsideLock(const std::shared_ptr<Submap>& previous);

  const SubmapCollectionConfig config_;
  mutable std::mutex mutex_;                                         // guards everything below
  std::map<SubmapId, std::shared_ptr<Submap>> submaps_;              // ids increase: creation order
  absl::flat_hash_map<KeyframeId, std::vector<SubmapId>> anchored_;  // anchor -> submaps
  std::shared_ptr<Submap> active_;
  SubmapId next_id_ = 0;
};

}  // namespace cblox
