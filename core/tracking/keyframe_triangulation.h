#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/features/scale_pyramid.h"
#include "core/geometry/se3.h"
#include "core/tracking/sparse_map.h"
#include "core/tracking/tracking_camera.h"

namespace cblox {

/// Settings of new landmarks triangulated between a keyframe and its covisible keyframes
/// (ORB-SLAM2's LocalMapping::CreateNewMapPoints with ORBmatcher::SearchForTriangulation,
/// stereo / RGB-D values).
struct KeyframeTriangulationConfig {
  /// Best covisible keyframes the new keyframe is matched with (ORB-SLAM2: 10 for stereo).
  int neighbours = 10;
  /// Matching: when neither feature has stereo depth, a candidate of b whose keypoint lies
  /// closer than this * sqrt(scale(level)) pixels to the epipole (the projection of a's
  /// centre) is rejected (ORB-SLAM2: squared distance < 100 * scale, i.e. 10).
  double epipole_radius_factor = 10.0;
  /// Matching: squared distance (pixels^2) of b's keypoint to the epipolar line of a's
  /// keypoint, in units of b's level variance sigma2(level), must be below this (ORB-SLAM2:
  /// 3.84, the 95% chi2 quantile of one degree of freedom).
  double epipolar_chi2 = 3.84;
  /// Matching: keep only matches whose keypoint rotation agrees with the dominant one
  /// (consistentRotations of feature_matcher.h). ORB-SLAM2's CreateNewMapPoints constructs
  /// its matcher without this check; we keep it on as a cheap outlier filter.
  bool check_orientation = true;
  /// Triangulation of two features without stereo depth needs rays at more than
  /// acos(this) apart (ORB-SLAM2: 0.9998, about 1.15 degrees).
  double max_mono_parallax_cos = 0.9998;
  /// Reprojection errors (pixels^2, in units of sigma2 of the feature's level) must be
  /// below these: 2 residuals (u, v) for a feature without stereo, 3 (u, v, u_right) with
  /// stereo (ORB-SLAM2: 5.991 and 7.8, the 95% chi2 quantiles).
  double chi2_mono = 5.991;
  double chi2_stereo = 7.8;
  /// Scale consistency: dist_b / dist_a (distances of the point to the two camera centres)
  /// must lie within [r / f, r * f] of r = scale(level_a) / scale(level_b), with
  /// f = scale_ratio_factor * the pyramid's scale factor (ORB-SLAM2: 1.5).
  double scale_ratio_factor = 1.5;

  /// Empty when valid, else a message naming the first bad field. Thread-safe.
  std::string validate() const;
};

/// A feature match between keyframes a and b and the point triangulated from it (G frame).
struct TriangulatedMatch {
  uint32_t index_a = 0, index_b = 0;
  Eigen::Vector3d p_G = Eigen::Vector3d::Zero();
};

/// The fundamental matrix F_ab of two views of one pinhole camera: pixel coordinates
/// (homogeneous) of the same point satisfy x_a^T F_ab x_b = 0, and F_ab^T x_a is the
/// epipolar line of x_a in b (ORB-SLAM2's ComputeF12). Thread-safe (pure).
Eigen::Matrix3d fundamentalMatrix(const Transformationd& T_A_G, const Transformationd& T_B_G,
                                  const PinholeIntrinsics& intrinsics);

/// Linear (DLT) triangulation of normalised image coordinates xn_a, xn_b ((u - cx) / fx,
/// (v - cy) / fy) seen from cameras at T_A_G and T_B_G: the right singular vector of the
/// smallest singular value of the 4 x 4 system, dehomogenised. Empty when that vector is at
/// infinity or not finite. Does not check that the point is in front of the cameras.
/// Thread-safe (pure).
std::optional<Eigen::Vector3d> triangulateLinear(const Eigen::Vector2d& xn_a,
                                                 const Eigen::Vector2d& xn_b,
                                                 const Transformationd& T_A_G,
                                                 const Transformationd& T_B_G);

/// ORB-SLAM2's SearchForTriangulation: matches the features of a and b that observe no
/// landmark in either keyframe, comparing only features in the same vocabulary node
/// (FeatureVectors must have been computed; none: no match). For each feature of a the
/// closest descriptor of b (distance <= kOrbDistanceLow) that lies near the epipolar line
/// and, when neither feature has stereo depth, away from the epipole (see the config); each
/// feature of b is matched at most once (first come); then the rotation check. Writes
/// (index in a, index in b) pairs, ascending in a, into *matches (cleared) and returns their
/// number. Uses the keyframes' current poses. Needs the map's shared lock.
int searchForTriangulation(const Keyframe& a, const Keyframe& b, const TrackingCamera& camera,
                           const ScalePyramid& pyramid, const KeyframeTriangulationConfig& config,
                           std::vector<std::pair<uint32_t, uint32_t>>* matches);

/// ORB-SLAM2's per-match triangulation of CreateNewMapPoints: for features index_a of a
/// (pose T_A_G) and index_b of b (T_B_G), the point by linear triangulation when the rays'
/// parallax exceeds the stereo parallax of both features (and, without stereo, the minimum
/// of the config), else the stereo point of the feature with the larger stereo parallax;
/// then rejected when behind either camera, when a reprojection error exceeds its chi2
/// bound, or when the distance ratio contradicts the levels. Empty when rejected.
/// Thread-safe (pure: reads the immutable features only).
std::optional<Eigen::Vector3d> triangulateMatch(
    const FrameFeatures& a, const Transformationd& T_A_G, uint32_t index_a, const FrameFeatures& b,
    const Transformationd& T_B_G, uint32_t index_b, const TrackingCamera& camera,
    const ScalePyramid& pyramid, const KeyframeTriangulationConfig& config);

/// searchForTriangulation followed by triangulateMatch for every match: the new points
/// between a and b (nothing when the camera centres are closer than the stereo baseline).
/// Needs the map's shared lock.
std::vector<TriangulatedMatch> triangulateNewPoints(const Keyframe& a, const Keyframe& b,
                                                    const TrackingCamera& camera,
                                                    const ScalePyramid& pyramid,
                                                    const KeyframeTriangulationConfig& config);

/// Makes landmarks of triangulated points: each gets its reference keyframe a, an
/// observation in both keyframes, its descriptor and its normal / distance range (as the
/// tracker's new landmarks). A point whose feature meanwhile observes a landmark in a or b,
/// or with a or b culled, is skipped. Returns the new landmarks. Needs the map's exclusive
/// lock.
std::vector<std::shared_ptr<Landmark>> addTriangulatedLandmarks(
    SparseMap* map, Keyframe* a, Keyframe* b, const std::vector<TriangulatedMatch>& points,
    const ScalePyramid& pyramid);

/// ORB-SLAM2's CreateNewMapPoints for stereo / RGB-D: triangulates new landmarks between
/// `keyframe` and each of its config.neighbours best covisible keyframes, in order. Before
/// each neighbour after the first, `stop_early` (if set) is asked whether to stop (a new
/// keyframe waits). Takes the map's lock itself (call without holding it): matching and
/// triangulation run under the shared lock, each neighbour's landmarks are added under the
/// exclusive lock; a neighbour's points are dropped when a loop correction or global BA
/// (SparseMap::changeIndex) moved the poses meanwhile. Returns the new landmarks. Call from
/// one thread at a time per map (the local mapping thread).
std::vector<std::shared_ptr<Landmark>> createNewLandmarks(
    SparseMap* map, Keyframe* keyframe, const TrackingCamera& camera, const ScalePyramid& pyramid,
    const KeyframeTriangulationConfig& config, const std::function<bool()>& stop_early = {});

}  // namespace cblox
