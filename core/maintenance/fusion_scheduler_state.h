#pragma once

// The part of the map maintenance's memory (FusionScheduler) that a resumed mapper needs to
// continue as if it had not stopped: the landmark sets of each subvolume's keyframes (the
// subvolume covisibility graph's edge weights follow from their unions exactly, and the
// keyframe pair asked about for a candidate from the keyframes' own sets) and the back-off of
// pairs the covariance test rejected. Plain values, saved in the map manifest
// (core/persistence/map_manifest.h).

#include <cstdint>
#include <string>
#include <vector>

namespace cblox {

/// The landmark ids one keyframe observed.
struct KeyframeLandmarks {
  /// The keyframe; kUnknownKeyframe for landmarks whose keyframe is not known (a version 2
  /// map manifest kept only the subvolume's union).
  int64_t keyframe = 0;
  std::vector<uint64_t> landmark_ids;  ///< strictly ascending

  static constexpr int64_t kUnknownKeyframe = -1;
  friend bool operator==(const KeyframeLandmarks&, const KeyframeLandmarks&) = default;
};

/// The keyframes that contributed to subvolume `subvolume` with their landmarks; L_s is the
/// union of their sets.
struct SubvolumeLandmarks {
  int64_t subvolume = 0;
  /// Strictly ascending keyframe ids (kUnknownKeyframe, if present, first).
  std::vector<KeyframeLandmarks> keyframes;

  friend bool operator==(const SubvolumeLandmarks&, const SubvolumeLandmarks&) = default;
};

/// A candidate pair that must wait before it is requested again.
struct FusionPairBackoff {
  int64_t older = 0;
  int64_t newer = 0;        ///< older < newer
  int32_t rejections = 0;   ///< rejections by q in a row (0: it waits after an error)
  double retry_in_s = 0.0;  ///< seconds left before it may be requested again (>= 0)

  friend bool operator==(const FusionPairBackoff&, const FusionPairBackoff&) = default;
};

/// FusionScheduler::exportState / restoreState. Requests in flight and fusions in progress
/// are not part of it: after a restart they are asked for again.
struct FusionSchedulerState {
  std::vector<SubvolumeLandmarks> subvolumes;  ///< strictly ascending subvolume ids
  std::vector<FusionPairBackoff> backoffs;     ///< strictly ascending (older, newer)

  bool empty() const { return subvolumes.empty() && backoffs.empty(); }
  /// Empty when well-formed, otherwise what is wrong (orders above, keyframe ids >= 0 or
  /// kUnknownKeyframe, older < newer, rejections >= 0, retry_in_s finite and >= 0).
  /// Thread-safe (pure).
  std::string validate() const;

  friend bool operator==(const FusionSchedulerState&, const FusionSchedulerState&) = default;
};

}  // namespace cblox
