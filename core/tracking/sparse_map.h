#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <shared_mutex>
#include <utility>
#include <vector>

#include <absl/container/flat_hash_map.h>
#include <Eigen/Core>

#include "core/tracking/keyframe.h"
#include "core/tracking/landmark.h"
#include "core/tracking/sparse_map_snapshot.h"

namespace cblox {

/// Poses of keyframes (T_G_C) after they changed, for CBLOX_KEYFRAME_POSES.
using KeyframePoseBatch = std::vector<std::pair<KeyframeId, Transformationd>>;

/// Where a keyframe's pose comes from: `ancestor` is the keyframe itself when it is good, or
/// the first good keyframe up its chain of parents when it is culled, and T_A_K its pose
/// relative to that ancestor (the product of the culled keyframes' T_parent_this; identity
/// for a good keyframe). A culled keyframe is rigidly tied to its ancestor from then on.
struct KeyframeAncestor {
  const Keyframe* ancestor = nullptr;
  Transformationd T_A_K;
};

/// The sparse SLAM map: keyframes and landmarks, owned here.
///
/// Concurrency (the one rule of core/tracking): every Keyframe and Landmark field that can
/// change, and this map's containers, are guarded by mutex(). The tracking thread reads under
/// a shared lock; local mapping and loop closing modify under an exclusive lock and do their
/// long computations (bundle adjustment, pose-graph optimisation) on copies taken under a
/// shared lock, writing results back under an exclusive lock. Methods of this class do not
/// lock: the caller holds the lock the method's comment names.
///
/// Lifetimes: keyframes are never freed while the map lives (culling marks them bad), so raw
/// Keyframe pointers stay valid. A retired landmark is removed from every keyframe and from
/// this map under the exclusive lock; frames of the tracker hold std::shared_ptr<Landmark>
/// and may keep one alive after it is retired (they check bad()).
class SparseMap {
 public:
  /// Most keyframe ids restore() skips above a snapshot (each costs a stand-in keyframe).
  static constexpr KeyframeId kMaxSkippedKeyframeIds = KeyframeId{1} << 16;

  SparseMap() = default;
  SparseMap(const SparseMap&) = delete;
  SparseMap& operator=(const SparseMap&) = delete;

  std::shared_mutex& mutex() const { return mutex_; }

  /// Adds a keyframe with the next keyframe id (0, 1, 2, ...). Exclusive lock.
  Keyframe* addKeyframe(uint64_t frame_id, int64_t timestamp_ns,
                        std::shared_ptr<const FrameFeatures> features,
                        const Transformationd& T_C_G);
  /// Adds a landmark with the next landmark id. Exclusive lock.
  std::shared_ptr<Landmark> addLandmark(const Eigen::Vector3d& p_G, Keyframe* reference);

  /// Makes `keyframe`'s feature `index` observe `landmark` (both directions). Exclusive lock.
  static void addObservation(Keyframe* keyframe, uint32_t index, Landmark* landmark);
  /// Removes that observation (both directions). Exclusive lock.
  static void eraseObservation(Keyframe* keyframe, uint32_t index);

  /// Retires a landmark: removed from every observing keyframe and from the map, marked bad.
  /// The map's reference is dropped, so `landmark` may be freed by the call unless a frame
  /// holds a shared_ptr to it: do not use the pointer afterwards. Exclusive lock.
  void retireLandmark(Landmark* landmark);
  /// Replaces `landmark` by `by` everywhere (ORB-SLAM2's MapPoint::Replace): observations
  /// move to `by` unless that keyframe already observes `by`; visible/found counters add up;
  /// `landmark` is retired with replacement() = by. Exclusive lock.
  void replaceLandmark(Landmark* landmark, Landmark* by);
  /// Culls a keyframe (Keyframe::cull) and retires the landmarks it orphaned. Exclusive lock.
  void cullKeyframe(Keyframe* keyframe);
  /// The good keyframe `keyframe`'s pose follows (see KeyframeAncestor); nullopt for a
  /// culled keyframe whose chain of parents ends without a good one (a stand-in that
  /// restore() made for a skipped id, which has no parent). With `stop`, the walk also ends
  /// at the first keyframe of the chain (`keyframe` included) for which it holds, culled or
  /// not. Shared lock.
  static std::optional<KeyframeAncestor> goodAncestor(
      const Keyframe* keyframe, const std::function<bool(const Keyframe&)>& stop = nullptr);
  /// Keeps culled keyframes' poses on their ancestors (ORB-SLAM2 recovers a culled keyframe's
  /// pose as its parent's times T_parent_this; here the dense mapper anchors subvolumes on
  /// keyframes, and a culled anchor must go on moving with the map): every culled keyframe
  /// whose good ancestor has an entry in `batch` (it just moved) gets the pose
  /// T_G_A(batch) * T_A_K, stored and appended to the batch. Entries of culled keyframes
  /// already in the batch are left as they are. Exclusive lock.
  void moveCulledKeyframes(KeyframePoseBatch* batch);

  /// Replaces the content of an empty map (no keyframe ever added) by a snapshot's. The map
  /// then continues with keyframe id max(snapshot.keyframes.size(), next_keyframe_id) and
  /// landmark id max(snapshot.next_landmark_id, next_landmark_id); keyframe ids skipped by
  /// that are culled stand-ins without features (ids another process may have seen before
  /// a crash are never reused; at most kMaxSkippedKeyframeIds of them). Every keyframe's
  /// features must hold their grid (and BoW vector, for relocalization). Throws
  /// std::invalid_argument when the map is not empty, the snapshot is inconsistent
  /// (SparseMapSnapshot::validate(pyramid_levels)) or the floors skip too many ids, leaving
  /// the map empty. Exclusive lock.
  void restore(const SparseMapSnapshot& snapshot, int pyramid_levels,
               KeyframeId next_keyframe_id = 0, LandmarkId next_landmark_id = 0);

  /// Shared lock for all of these.
  Keyframe* keyframe(KeyframeId id) const;
  std::shared_ptr<Landmark> landmark(LandmarkId id) const;
  /// Good keyframes by increasing id.
  std::vector<Keyframe*> keyframes() const;
  /// Every keyframe ever added, bad ones included, by id (index = id).
  const std::vector<std::unique_ptr<Keyframe>>& allKeyframes() const { return keyframes_; }
  /// Good landmarks by increasing id.
  std::vector<Landmark*> landmarks() const;
  size_t numKeyframes() const { return num_good_keyframes_; }
  size_t numLandmarks() const { return landmarks_.size(); }
  /// The id the next landmark will get.
  LandmarkId nextLandmarkId() const { return next_landmark_id_; }

  /// The map's "big change" counter, bumped by loop closure and global BA so the tracker
  /// knows poses jumped. Shared lock to read, exclusive to bump.
  int changeIndex() const { return change_index_; }
  void bumpChangeIndex() { ++change_index_; }
  /// True while a loop correction is half done: between LoopCloser::correct's two exclusive
  /// phases the query's covisible group is corrected and the rest of the map is not yet (its
  /// essential graph is being solved without the lock). Local mapping starts no local BA then:
  /// the keyframes it would hold fixed may be the uncorrected ones. Shared lock to read,
  /// exclusive to set.
  bool correctionPending() const { return correction_pending_; }
  void setCorrectionPending(bool pending) { correction_pending_ = pending; }
  /// The stereo disparity correction in use, pixels (DisparityCorrection): new frames are
  /// built with it, and bundle adjustments take every stored stereo column corrected by it
  /// (featureMeasurement's correction). No lock needed (atomic).
  float disparityCorrectionPx() const {
    return disparity_correction_px_.load(std::memory_order_relaxed);
  }
  void setDisparityCorrectionPx(float px) {
    disparity_correction_px_.store(px, std::memory_order_relaxed);
  }

 private:
  mutable std::shared_mutex mutex_;
  std::vector<std::unique_ptr<Keyframe>> keyframes_;
  size_t num_good_keyframes_ = 0;
  absl::flat_hash_map<LandmarkId, std::shared_ptr<Landmark>> landmarks_;
  LandmarkId next_landmark_id_ = 0;
  bool correction_pending_ = false;
  int change_index_ = 0;
  std::atomic<float> disparity_correction_px_{0.0f};
};

}  // namespace cblox
