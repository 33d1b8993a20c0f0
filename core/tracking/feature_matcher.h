#pragma once

#include <cstdint>
#include <vector>

#include "core/features/scale_pyramid.h"
#include "core/tracking/frame.h"
#include "core/tracking/keyframe.h"
#include "core/tracking/tracking_camera.h"

namespace cblox {

/// Descriptor-distance thresholds of ORB-SLAM2's ORBmatcher (Hamming distance of 256 bits).
inline constexpr int kOrbDistanceHigh = 100;
inline constexpr int kOrbDistanceLow = 50;

/// Where a landmark is expected in a frame (ORB-SLAM2's Frame::isInFrustum): its projection
/// (pixels), the virtual right coordinate, the predicted pyramid level and the cosine
/// between the viewing ray and the landmark's mean viewing direction.
struct LandmarkProjection {
  Landmark* landmark = nullptr;
  float u = 0.0f, v = 0.0f, u_right = 0.0f;
  int level = 0;
  float view_cos = 1.0f;
};

/// Settings shared by the matching functions.
struct FeatureMatcherConfig {
  /// Best / second-best distance ratio a match must beat (ORB-SLAM2: 0.8 for projection
  /// search in tracking, 0.7 for BoW search, 0.6 for BoW in relocalization).
  float nn_ratio = 0.8f;
  /// Keep only matches whose rotation change agrees with the dominant one
  /// (consistentRotations; ORB-SLAM2's orientation consistency check).
  bool check_orientation = true;
  /// Largest descriptor distance of a projection match (searchLocalLandmarks,
  /// searchLastFrame): ORB-SLAM2's TH_HIGH (100) in tracking, TH_LOW (50) when verifying a
  /// loop.
  int max_distance = kOrbDistanceHigh;
};

/// Projects a landmark into a camera at T_C_G: empty when it is behind the camera, outside
/// the image, out of its scale-invariance distance range, or seen at more than
/// acos(min_view_cos) from its mean viewing direction. Needs the map's shared lock.
/// Thread-safe otherwise (pure).
std::optional<LandmarkProjection> projectLandmark(Landmark* landmark, const Transformationd& T_C_G,
                                                  const TrackingCamera& camera,
                                                  const ScalePyramid& pyramid,
                                                  float min_view_cos = 0.5f);

/// Matches landmarks expected in `frame` (projections from projectLandmark at the frame's
/// predicted pose) to its unmatched features within a window of radius
/// th * (2.5 if view_cos > 0.998 else 4) * scale(level) around each projection, features
/// of level [level - 1, level], descriptor distance <= config.max_distance and the ratio
/// test (unless both best candidates share a level). Features already holding a landmark
/// with observations are not re-matched. Returns the number of new matches (ORB-SLAM2's
/// SearchByProjection for the local map). Needs the map's shared lock.
int searchLocalLandmarks(Frame* frame, const std::vector<LandmarkProjection>& projections, float th,
                         const FeatureMatcherConfig& config, const ScalePyramid& pyramid);

/// Matches the landmarks of `last` (non-outlier matches) into `current`, whose predicted
/// pose must be set: projections within th * scale(last octave) px, octave window chosen by
/// the camera's forward/backward motion for stereo, distance <= config.max_distance,
/// orientation check. Returns the number of matches (ORB-SLAM2's SearchByProjection with a
/// motion model). Needs the map's shared lock.
int searchLastFrame(Frame* current, const Frame& last, float th, const TrackingCamera& camera,
                    const ScalePyramid& pyramid, const FeatureMatcherConfig& config);

/// Matches the landmarks of `keyframe` to the features of `frame` within the same vocabulary
/// node (FeatureVector; both must have been computed), distance <= kOrbDistanceLow and the
/// ratio test, orientation check. Writes the matched landmarks into matches (one per frame
/// feature, nullptr: none; resized) and returns their number (ORB-SLAM2's SearchByBoW for
/// tracking/relocalization). Needs the map's shared lock.
int searchByBow(const Keyframe& keyframe, const FrameFeatures& frame,
                const FeatureMatcherConfig& config, std::vector<Landmark*>* matches);

/// Keyframe-to-keyframe BoW matching (for loop closing): for every feature of `a` holding a
/// good landmark, the best feature of `b` holding a good landmark in the same node. matches
/// gets, per feature of a, the landmark of b (nullptr: none). Needs the map's shared lock.
int searchByBow(const Keyframe& a, const Keyframe& b, const FeatureMatcherConfig& config,
                std::vector<Landmark*>* matches);

/// Keeps only the matches whose keypoint rotation change (angle_b - angle_a in degrees, any
/// range) lies within 30 degrees of the dominant change: the circular mean of the changes
/// in the densest window of three adjacent 10-degree bins of their histogram. ORB-SLAM2
/// keeps the three fullest histogram bins instead (the second and third only above 10% of
/// the first), which on smooth textures threw away 10-15% of correct frame-to-frame matches
/// whose orientation (intensity centroid) changed by 6-25 degrees. `rotations[i]` is the
/// change of match i; returns the indices to keep, ascending (empty for no input).
/// Thread-safe (pure).
std::vector<size_t> consistentRotations(const std::vector<float>& rotations);

}  // namespace cblox
