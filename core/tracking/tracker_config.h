#pragma once

#include <string>

namespace cblox {

/// Settings of the tracking thread (ORB-SLAM2's Tracking). Defaults are ORB-SLAM2's stereo
/// values; frame counts are frames the tracker has processed (not source frame ids). For
/// street drives at speed the keyframe decision can be bounded (README "Keyframes on a street
/// drive": reference_ratio 0.5 and the close-point gap's three settings below).
struct TrackerConfig {
  /// Stereo initialisation needs this many features with depth (ORB-SLAM2: 500).
  int min_features_to_initialize = 500;
  /// A new keyframe creates landmarks from its unmatched features with depth, closest
  /// first: all closer than the camera's close_depth_m, and at least this many (100).
  int min_new_landmarks_per_keyframe = 100;
  /// Keyframe decision: at most / at least this many frames between keyframes. max is
  /// ORB-SLAM2's "fps" (a keyframe at least once per second), min its 0.
  int max_frames_between_keyframes = 20;
  int min_frames_between_keyframes = 0;
  /// A keyframe is needed when the frame tracks fewer than this fraction of the reference
  /// keyframe's landmarks (0.75 stereo; 0.4 while the map has one keyframe)...
  double reference_ratio = 0.75;
  /// ... or when fewer than tracked_close_min close features are tracked and more than
  /// untracked_close_min close features could become landmarks (100 / 70).
  int tracked_close_min = 100;
  int untracked_close_min = 70;
  /// The close-point rule only once this many frames have passed since the last keyframe
  /// (0 = at any frame, ORB-SLAM2's). On a street at speed the close road and walls are new
  /// in every frame, and without the gap the rule alone made a keyframe every 2.7 frames
  /// (BENCHMARKS.md). 0 by default: in a small indoor scene the gap cuts the keyframes about
  /// 4x, and the dense mapper's subvolumes are a number of keyframes long (README).
  int close_points_min_frames = 0;
  /// ... or once the camera has turned more than this many degrees since the last keyframe
  /// (0 = the gap always holds): at a turn the view changes in a few frames, and a gap that
  /// held there lost the town's 12 m-radius turn.
  double close_points_turn_deg = 0.0;
  /// ... or once the frame has fewer than this many inliers (0 = off). Where few far
  /// landmarks are in view (the town's turn at its west edge, facing open land) the road's
  /// close points are most of what is tracked and leave the image within frames: with a gap
  /// of 8 frames the inliers fell from about 100 to 40 over 30 frames and the next frame was
  /// lost; with this floor at 100 they stayed above 59 (BENCHMARKS.md).
  int close_points_gap_min_inliers = 0;
  /// Projection search windows (pixels, times the level's scale): against the last frame
  /// (7 for stereo in ORB-SLAM2, doubled when too few matches), against the local map (1;
  /// 5 just after relocalization).
  float last_frame_search_radius = 7.0f;
  float local_map_search_radius = 1.0f;
  float relocalized_search_radius = 5.0f;
  /// Matches needed: motion model / reference keyframe search (20 / 15), inliers after pose
  /// optimisation (10), inliers after tracking the local map (30; 50 within
  /// max_frames_between_keyframes frames of a relocalization, and a relocalization candidate
  /// is accepted only when PnP plus a guided search of its landmarks reach those 50).
  int min_motion_model_matches = 20;
  int min_reference_matches = 15;
  int min_pose_inliers = 10;
  int min_local_map_inliers = 30;
  int min_local_map_inliers_after_relocalization = 50;
  /// Local map: keyframes sharing landmarks with the frame, their best covisible
  /// neighbours, children and parents, at most this many (80).
  int max_local_keyframes = 80;
  /// Relocalization: candidates from the keyframe database (at most this many), BoW matches
  /// needed per candidate (15), RANSAC PnP iterations (300) and reprojection threshold (px).
  int max_relocalization_candidates = 20;
  int min_relocalization_matches = 15;
  int pnp_iterations = 300;
  double pnp_reprojection_error_px = 4.0;

  /// Empty when valid, else a message naming the field. Thread-safe.
  std::string validate() const;
};

}  // namespace cblox
