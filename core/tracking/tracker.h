#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/features/scale_pyramid.h"
#include "core/optimization/stereo_camera_model.h"
#include "core/tracking/frame.h"
#include "core/tracking/keyframe_sink.h"
#include "core/tracking/sparse_map.h"
#include "core/tracking/tracker_config.h"
#include "core/tracking/tracking_camera.h"
#include "core/vocabulary/binary_vocabulary.h"
#include "core/vocabulary/keyframe_database.h"

namespace cblox {

enum class TrackingState {
  kNotInitialized,  ///< no map yet: waiting for a frame with enough features with depth
  kOk,              ///< pose tracked against the map
  kLost,            ///< tracking failed; relocalization is tried on every frame
};

const char* trackingStateName(TrackingState state);

/// Which of ORB-SLAM2's keyframe conditions let a keyframe through (c1 of NeedNewKeyFrame;
/// c2, fewer inliers than reference_ratio of the reference keyframe's tracked landmarks or
/// close points needed, holds in every case).
enum class KeyframeReason : uint8_t {
  kNone,          ///< no keyframe from this frame
  kMaxFrames,     ///< max_frames_between_keyframes frames since the last keyframe
  kClosePoints,   ///< too few tracked close points and enough untracked ones
  kWeakTracking,  ///< fewer inliers than a quarter of the reference keyframe's landmarks
  kMapperIdle,    ///< min_frames_between_keyframes passed and local mapping was idle
};
/// "none", "max_frames", "close_points", "weak_tracking", "mapper_idle". Thread-safe.
const char* keyframeReasonName(KeyframeReason reason);

/// What tracking one frame gave.
struct TrackingResult {
  TrackingState state = TrackingState::kNotInitialized;
  /// The frame's pose (world to camera) when state is kOk.
  std::optional<Transformationd> T_C_G;
  /// The frame was relocalized (its pose jumped relative to the motion before it).
  bool relocalized = false;
  /// The frame initialised the map.
  bool initialized = false;
  /// Loop closure or global BA moved the map since the previous frame (poses jumped).
  bool map_corrected = false;
  /// A keyframe made from this frame (already in the map and handed to the sink).
  Keyframe* new_keyframe = nullptr;
  /// Why the keyframe was made (kNone without one, and for the map's first keyframe).
  KeyframeReason keyframe_reason = KeyframeReason::kNone;
  /// The keyframe the frame was tracked against when state is kOk: of the local map's
  /// keyframes, the one sharing the most landmarks with the frame (ORB-SLAM2's reference
  /// keyframe), or the keyframe made from this frame; -1 otherwise.
  int64_t reference_keyframe = -1;
  /// Inlier matches after the last pose optimisation.
  int inliers = 0;
  /// Why tracking failed (empty when state is kOk).
  std::string reason;
  /// Milliseconds spent in track() (features excluded: they are built before).
  double time_ms = 0.0;
  /// Of time_ms, the milliseconds spent waiting for the map's lock (held exclusively by local
  /// mapping or loop closing meanwhile).
  double map_wait_ms = 0.0;
};

/// ORB-SLAM2's tracking thread logic for stereo and RGB-D (no threads of its own): stereo
/// initialisation, tracking with a constant-velocity motion model or against the reference
/// keyframe, tracking the local map, keyframe decision and creation, relocalization with
/// BoW candidates + PnP RANSAC when lost.
///
/// Thread-safety: not thread-safe; one tracking thread calls track(). It takes the map's
/// shared lock while reading the map and the exclusive lock to insert a keyframe.
class Tracker {
 public:
  /// `map` must outlive the tracker; `database` (may be null: no relocalization), `sink`
  /// (may be null: keyframes are only added to the map) and `vocabulary` (may be null: no
  /// BoW vectors, so no relocalization and the reference keyframe is searched by projection)
  /// too. Throws std::invalid_argument for an invalid camera or config, or for a database
  /// without a vocabulary.
  Tracker(SparseMap* map, const TrackingCamera& camera, const ScalePyramid& pyramid,
          const TrackerConfig& config, const KeyframeDatabase* database, KeyframeSink* sink,
          const BinaryVocabulary* vocabulary = nullptr);

  /// Tracks one frame (features from a FrameBuilder). `frame_id` and `timestamp_ns` must
  /// increase. `T_C_G_initial`: the pose of the first keyframe when this frame initialises the
  /// map (identity when absent).
  /// BoW vectors are computed lazily, as ORB-SLAM2 does: the tracker fills `features->bow` and
  /// `feature_vector` (with the vocabulary, when they are empty) only when it needs them: the
  /// reference-keyframe search, relocalization, and before the frame becomes a keyframe (so
  /// every keyframe has them before other threads see it). A frame the motion model tracks
  /// and that makes no keyframe never pays for them (1.3 ms with the default vocabulary).
  /// The features must not be shared with another thread while the call runs.
  TrackingResult track(uint64_t frame_id, int64_t timestamp_ns,
                       std::shared_ptr<FrameFeatures> features,
                       const std::optional<Transformationd>& T_C_G_initial = std::nullopt);

  /// After the map was restored from a snapshot (SparseMap::restore): the tracker is lost in
  /// that map, so the next frames relocalize against its keyframes.
  void resumeLost();

  /// Runs on the tracking thread each time a frame has been tracked and the map's shared lock
  /// released, before the frame's keyframe (if it makes one) is inserted under the exclusive
  /// lock: the window in which loop closing or local mapping may move the map's poses. The
  /// tracker re-expresses the frame's pose on its reference keyframe after this window, so a
  /// correction there moves the frame with the map. Its argument: whether the frame makes a
  /// keyframe. Tests move the map from this hook; empty (the default) runs nothing.
  void setAfterTrackingHook(std::function<void(bool makes_keyframe)> hook) {
    after_tracking_hook_ = std::move(hook);
  }

  TrackingState state() const { return state_; }
  /// The last tracked frame (its pose is set when the state is kOk).
  const Frame& lastFrame() const { return last_frame_; }

 private:
  bool initialize(const std::optional<Transformationd>& T_C_G_initial, TrackingResult* result);
  // The current frame's BoW vectors, when there is a vocabulary and they are not computed.
  void computeBow();
  /// Match counts of the searches that track a frame before the local map: the last frame at
  /// the velocity's pose (matches in its last window, inliers after the pose), the reference
  /// keyframe (by BoW, or projected without a vocabulary). -1: not tried. For the reason
  /// given when both fail.
  struct FrameSearchCounts {
    int motion_matches = -1, motion_inliers = -1;
    int reference_matches = -1, reference_inliers = -1;
  };
  bool trackWithMotionModel(int* matches, int* inliers);
  bool trackReferenceKeyframe(int* matches, int* inliers);
  static std::string frameSearchFailure(const FrameSearchCounts& counts);
  bool relocalize();
  /// Matches the keyframe's landmarks not yet matched in the current frame, projected at
  /// its pose, in a window `th` (see searchLocalLandmarks). Returns the new matches.
  int searchKeyframeLandmarks(const Keyframe& keyframe, float th);
  bool trackLocalMap(TrackingResult* result);
  int optimizeCurrentPose();
  void updateLocalMap();
  int searchLocalMap();
  KeyframeReason needNewKeyframe(int inliers) const;
  // The close-point rule's gap: close_points_min_frames since the last keyframe, or a turn of
  // more than close_points_turn_deg since it, or fewer than close_points_gap_min_inliers
  // inliers in the frame.
  bool closePointGapPassed(int inliers) const;
  Keyframe* createKeyframe();
  void replaceRetiredInLastFrame();
  // The last frame's pose follows its reference keyframe's (moved by local BA or loop
  // closure since): ORB-SLAM2's UpdateLastFrame.
  void updateLastFramePose();
  // The current frame's pose from its reference keyframe's present pose and
  // T_current_reference_ (the map's lock held): a correction made since the frame was tracked
  // moves it too. Without this a keyframe made right after a loop correction kept the
  // uncorrected pose, and its new landmarks were placed there.
  void followReferenceKeyframe();

  SparseMap* map_;
  TrackingCamera camera_;
  StereoCameraModel model_;
  ScalePyramid pyramid_;
  TrackerConfig config_;
  const KeyframeDatabase* database_;
  KeyframeSink* sink_;
  const BinaryVocabulary* vocabulary_;

  TrackingState state_ = TrackingState::kNotInitialized;
  uint64_t frames_processed_ = 0;  // counter behind the keyframe decision
  uint64_t current_index_ = 0;     // frames_processed_ of the current frame
  uint64_t last_keyframe_index_ = 0;
  // R_C_G of the current frame when the last keyframe was made (close_points_turn_deg).
  Eigen::Quaterniond last_keyframe_rotation_ = Eigen::Quaterniond::Identity();
  uint64_t last_relocalization_index_ = 0;
  bool ever_relocalized_ = false;
  int map_change_index_ = 0;
  Frame current_;
  // current_.features, writable for computeBow() until the frame is shared as a keyframe.
  std::shared_ptr<FrameFeatures> current_features_;
  Frame last_frame_;
  std::optional<Transformationd> velocity_;  // T_Ccur_Clast
  Keyframe* reference_keyframe_ = nullptr;
  // T_Ccur_Kref of the current frame, read under the lock it was tracked with: after that lock
  // is released the map may move (a loop correction, a global BA), and the frame follows its
  // reference keyframe (followReferenceKeyframe).
  Transformationd T_current_reference_;
  std::function<void(bool)> after_tracking_hook_;
  Keyframe* last_reference_ = nullptr;  // last frame's reference keyframe
  Transformationd T_last_reference_;    // T_Clast_Kref
  std::vector<Keyframe*> local_keyframes_;
  /// The local map's landmarks, valid while the map's lock taken by track() is held.
  std::vector<Landmark*> local_landmarks_;
  std::vector<Keyframe*> observers_;  // updateLocalMap's scratch
};

}  // namespace cblox
