#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "core/submap/submap.h"

namespace cblox {

/// Settings of the subvolume creation rule.
struct SubmapCreationPolicyConfig {
  /// A submap collects at most this many keyframes (its anchor included); the next keyframe
  /// anchors a new submap. >= 1. Default 10: a few metres of travel per subvolume at usual
  /// keyframe rates; tune per platform.
  int max_keyframes_per_subvolume = 10;
  /// A keyframe farther than this from the active submap's anchor (its current T_G_M)
  /// anchors a new submap, metres (> 0), or 0: no bound. Bounds a subvolume's extent where
  /// keyframes are sparse (a revisit of mapped places adds few), so its anchor stays near
  /// what it holds (README, "Map maintenance"). Default 0 until measured over several runs.
  double max_anchor_distance_m = 0.0;
  /// Revisit anchoring, metres (> 0), or 0: off. A keyframe closer than this to the anchor
  /// of an older subvolume anchors a new submap, unless the active submap's anchor is itself
  /// within this distance of that older anchor (it already starts there). So when tracking
  /// returns to mapped places, the revisit's subvolumes start where the old ones did and
  /// their anchors are near the anchors of what they overlap: the relative pose the fusion
  /// asks about (q of the two anchors) is that of two nearby keyframes (README, "Map
  /// maintenance"). Positions are the current estimates (drift before a loop closes shifts
  /// them by as much). Keyframe-driven: a revisit the tracker follows without new keyframes
  /// (the hall's second lap adds 3) is not split. Measured (BENCHMARKS.md, "Why the hall's
  /// revisit is never fused"): town at 0.5 m voxels, 1.5 m, q_min 3e3: 70-71 % of the off
  /// size instead of 73-82 %, same RMSE (two runs); hall: no change. Default 0 (off) until
  /// measured over more runs.
  double revisit_anchor_distance_m = 0.0;
  /// Frame-driven revisit anchoring, frames (>= 1), or 0: off. Each frame names the keyframe
  /// it was tracked against (frame_pose_t::reference_keyframe_id); its home is the oldest
  /// submap that records that keyframe. A frame whose home is a finished submap with another
  /// anchor than the active submap's votes for that home; after this many consecutive votes
  /// for the same home, the frame starts a new submap anchored at the home's anchor keyframe
  /// (T_G_M = the home's), and it and the following frames are integrated there. So a revisit
  /// the tracker follows inside its known map, making no keyframe (the hall's second lap),
  /// goes into subvolumes that share an anchor with what they revisit: their relative pose is
  /// exact (the identity), and map maintenance fuses them without a covariance
  /// (FusionScheduler::takeSameAnchorPairs). The frames' poses are the tracker's, made
  /// against that home's landmarks, so the anchoring adds no uncertainty of its own. The votes
  /// keep a reference that flickers between neighbouring subvolumes (or lags behind a new
  /// keyframe) from starting a subvolume per frame. README, "Map maintenance". Default 10:
  /// measured (BENCHMARKS.md, "The frames rule by default") with q_min 3e3 and
  /// CovisibilityGraphConfig::min_shared_ratio 0.04, fusion keeps 59 % of the off size on the
  /// hall instead of 87 %, and the room and the town lose nothing by it, at the same RMSE.
  int revisit_after_frames = 10;
  /// With revisit_after_frames: a revisit submap (one started by that rule) whose frames keep
  /// being tracked against its home takes at most this many frames (>= 1); the next one
  /// starts a fresh revisit submap with the same anchor, and the full one, finished, is fused
  /// into its home at once. So a long revisit (a whole lap in a known map) never builds up
  /// in the one active submap, which map maintenance cannot fuse. 0: no bound. Default 30
  /// (1.5 s at 20 Hz; on the hall 100 left 7 % of the off size in the active subvolume).
  int revisit_max_frames = 30;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

/// The paper's subvolume creation rule, plus the little state the mapper needs to apply it.
///
/// Rule: a new submap is needed when the active one has max_keyframes_per_subvolume
/// keyframes, or when a frame pose arrives flagged as a tracking jump (relocalisation, loop
/// closure, map reset: frame_pose_t::tracking_jump). The new submap's frame is the pose of
/// the first keyframe after that decision, so the decision and the creation are two steps:
///
///     per frame pose (T_G_C, jump):
///       if (policy.onFramePose(collection.activeSubmap().get(), jump) ==
///           FrameAction::kIntegrate) integrate into the active submap with T_M_C;
///       else count the frame as waiting for an anchor (not integrated)
///     per new keyframe (id, T_G_K, time):
///       if (policy.onKeyframe(collection.activeSubmap().get()))
///         collection.createSubmap(T_G_K, id, time);       // anchor; previous finished
///       else collection.activeSubmap()->addKeyframe(id);
///
/// Frames after a keyframe-count decision still go into the active submap until the next
/// keyframe (the pose is continuous); frames after a tracking jump, and frames before the
/// first submap exists, wait (are not integrated) until the next keyframe anchors a new
/// submap, so no frame is fused across a discontinuity.
///
/// Thread safety: needsNewSubmap() is pure and thread-safe; the state (onFramePose,
/// onKeyframe, pending(), reset) is not: one thread drives an instance.
class SubmapCreationPolicy {
 public:
  /// Why the next keyframe will anchor a new submap.
  enum class Pending {
    kNone,            ///< no new submap pending (while an active submap exists)
    kNoActiveSubmap,  ///< there is no active submap yet (or it was finished)
    kKeyframeLimit,   ///< the active submap has max_keyframes_per_subvolume keyframes
    kTrackingJump,    ///< a frame pose was flagged as a tracking jump
  };
  /// What the mapper does with a frame whose pose it has.
  enum class FrameAction {
    kIntegrate,      ///< integrate into the active submap
    kWaitForAnchor,  ///< do not integrate: a new submap starts at the next keyframe
  };

  /// Throws std::invalid_argument with SubmapCreationPolicyConfig::validate()'s message.
  explicit SubmapCreationPolicy(const SubmapCreationPolicyConfig& config);

  /// The rule: true when tracking_jump, when `active` already has
  /// >= max_keyframes_per_subvolume keyframes, or when it is finished. Thread-safe (pure).
  bool needsNewSubmap(const Submap& active, bool tracking_jump) const;

  /// Applies the rule to a frame pose (`active`: the collection's active submap, or null).
  /// A tracking jump, or a missing/finished active submap, makes the next keyframe anchor a
  /// new submap and returns kWaitForAnchor until then; reaching the keyframe limit makes the
  /// next keyframe anchor a new submap but frames keep being integrated. A jump overrides a
  /// pending keyframe-limit decision. With the frame's time `frame_time_ns`, a jump is
  /// already answered (it is not one) when `active` was created at or after that time: the
  /// keyframe of the jump arrived, and anchored it, before the frame was processed.
  /// Not thread-safe.
  FrameAction onFramePose(const Submap* active, bool tracking_jump,
                          std::optional<int64_t> frame_time_ns = std::nullopt);

  /// Applies the rule to a new keyframe: true when it must anchor a new submap (something
  /// was pending, there is no active submap, or the active one is full); the pending state
  /// is then cleared and the caller creates the submap with T_G_M = T_G_K. False: the
  /// caller adds the keyframe to `active`. `starts_new_map`: the keyframe belongs to another
  /// map than the active submap's (the tracker started a new map): always a new submap, as
  /// after a jump. `keyframe_position` (p of T_G_K): with max_anchor_distance_m > 0, a
  /// keyframe farther than that from the active submap's anchor anchors a new one; with
  /// revisit_anchor_distance_m > 0, one near an anchor of `older_anchors` (the positions of
  /// the other submaps' anchors, any order) does, as that field says. Not thread-safe.
  bool onKeyframe(const Submap* active, bool starts_new_map = false,
                  const std::optional<Eigen::Vector3d>& keyframe_position = std::nullopt,
                  std::span<const Eigen::Vector3d> older_anchors = {});
  /// Where a frame's reference keyframe is: the oldest submap that records it.
  struct ReferenceHome {
    SubmapId submap = 0;
    KeyframeId anchor = 0;  ///< that submap's anchor keyframe
  };
  /// Applies the frame-driven revisit rule (revisit_after_frames) to a frame that is to be
  /// integrated into `active` (onFramePose returned kIntegrate); `home`: its reference
  /// keyframe's home, nullopt when it has none or no submap records it. True when the frame
  /// must start a revisit submap: the caller creates it with T_G_M = the home's current
  /// T_G_M, anchored at home->anchor, and integrates the frame into it; a pending
  /// keyframe-limit decision is cleared (lastReason() is kRevisitFrames). A frame whose home
  /// is `active`, or shares its anchor, or that has no home, clears the votes. When `active`
  /// is the revisit submap this rule started last (and no keyframe started another since),
  /// the frames at home are counted: the revisit_max_frames-th after its start returns true
  /// with the same home (a fresh revisit submap). A keyframe while that revisit submap is
  /// active starts a new submap (onKeyframe, kRevisitEnded): a revisit submap holds only
  /// frames tracked against its home. Always false when revisit_after_frames is 0. Not
  /// thread-safe.
  bool onFrameReference(const Submap& active, const std::optional<ReferenceHome>& home);
  /// The revisit rule for a frame that waits for an anchor after a tracking jump
  /// (onFramePose returned kWaitForAnchor with the jump pending): when its reference
  /// keyframe's `home` is an older submap (not `active`, not sharing its anchor), the frame
  /// starts a revisit submap there at once instead of waiting for the tracker's next keyframe
  /// (a loop closure or a relocalization in a known place: the tracker tracks against the old
  /// map and makes no keyframe, and every frame until one would be lost). True: the caller
  /// creates the submap as for onFrameReference and integrates the frame; the jump is no
  /// longer pending, the submap is the revisit submap of onFrameReference's rules, and
  /// lastReason() is kRevisitAfterJump. False when revisit_after_frames is 0, no jump is
  /// pending or the home does not qualify. Not thread-safe.
  bool onJumpReference(const Submap* active, const std::optional<ReferenceHome>& home);

  /// Why the last onKeyframe() or onFrameReference() that returned true created a submap
  /// (logs, benchmarks).
  enum class Reason {
    kNone,              ///< no submap created yet
    kNoActiveSubmap,    ///< there was no active submap (or it was finished)
    kNewMap,            ///< starts_new_map
    kTrackingJump,      ///< a frame pose was flagged as a tracking jump
    kKeyframeLimit,     ///< the active submap was full
    kRevisit,           ///< near an older anchor (revisit_anchor_distance_m)
    kAnchorDistance,    ///< far from the active anchor (max_anchor_distance_m)
    kRevisitFrames,     ///< frames tracked in an older subvolume (revisit_after_frames)
    kRevisitEnded,      ///< a keyframe while the active submap is a revisit submap
    kRevisitAfterJump,  ///< after a jump, tracked in an older subvolume (onJumpReference)
  };
  /// Not thread-safe.
  Reason lastReason() const { return last_reason_; }

  /// The pending decision. Not thread-safe.
  Pending pending() const { return pending_; }
  /// Forgets the pending decision and the revisit rule's state (e.g. after the mapper cleared
  /// its map). Not thread-safe.
  void reset() {
    pending_ = Pending::kNone;
    revisit_home_ = -1;
    revisit_votes_ = 0;
    revisit_anchor_ = -1;
    revisit_frames_ = 0;
  }

  const SubmapCreationPolicyConfig& config() const { return config_; }
  /// "no active submap", "new map", "tracking jump", "keyframe limit", "revisit",
  /// "anchor distance", "tracked in an older subvolume", "new keyframe after a revisit",
  /// "tracked in an older subvolume after a jump" ("none" for kNone).
  static const char* reasonName(Reason reason);

 private:
  // The frame is at home: its home is the active submap or shares its anchor.
  static bool atHome(const Submap& active, const ReferenceHome& home);
  // A revisit submap anchored at `anchor` starts (the caller creates it): the votes are
  // spent, its frames at home count from zero, nothing is pending. Returns true.
  bool startRevisit(KeyframeId anchor, Reason reason);

  SubmapCreationPolicyConfig config_;
  Pending pending_ = Pending::kNone;
  Reason last_reason_ = Reason::kNone;
  SubmapId revisit_home_ = -1;  // the home the current votes are for
  int revisit_votes_ = 0;
  // The revisit submap started last (its anchor) while it is the active one, and the frames
  // at home since; -1: the active submap is no revisit submap.
  KeyframeId revisit_anchor_ = -1;
  int revisit_frames_ = 0;
};

}  // namespace cblox
