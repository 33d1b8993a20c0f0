#pragma once

// A distance field's answers against the exact scene: sample points with their exact signed
// distance and whether a depth camera observed them as free space (sampleDistanceTruth), and
// the figures of a field's answers at those points (scoreDistanceField).

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/esdf/esdf_voxel.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"
#include "core/raycast/triangle_mesh_raycaster.h"

namespace cblox {

/// One depth image of the scene as the mapper integrated it: the true pose of the depth
/// camera (frame D: z forward, x right, y down) and the depths it measures. Plain value type.
struct DepthView {
  Transformationd T_G_D;
  PinholeIntrinsics intrinsics;
  double min_depth_m = 0.0;  ///< nearer depths are not measured
  double max_depth_m = 0.0;  ///< farther depths are not measured (no value at the pixel)
  /// Measurements farther than this from the camera centre (along the ray) are not
  /// integrated (the integrator's max_ray_length_m).
  double max_ray_length_m = std::numeric_limits<double>::infinity();
};

/// Options of sampleDistanceTruth(). Plain value type.
struct DistanceTruthConfig {
  /// Points drawn uniformly in `box` (frame G of the truth mesh). >= 1.
  size_t samples = 100000;
  Eigen::AlignedBox3d box;
  /// Seed of the points (std::mt19937_64, doubles made by hand: the same on any library).
  uint64_t seed = 20240601;
  /// A point is observed free when some view measured a surface behind it at least this
  /// far in depth (the TSDF's truncation: nearer, the point lies in the surface's band),
  /// plus free_margin_m (say one voxel, for the voxel around the point). Finite, >= 0.
  double truncation_m = 0.0;
  double free_margin_m = 0.0;
  /// Every view_stride-th view is used (>= 1).
  int view_stride = 1;
  /// Threads, in [1, 64]; the samples do not depend on it.
  int num_threads = 2;

  /// Empty when valid, else a message naming the bad field. Thread-safe.
  std::string validate() const;
};

/// One sample point with the truth about it.
struct DistanceTruthSample {
  Eigen::Vector3d p_G = Eigen::Vector3d::Zero();
  /// Exact distance to the closest surface point (double precision point-to-triangle),
  /// negative inside a solid.
  double signed_distance_m = 0.0;
  /// Some view saw through the point: inside its image and depth range, with the surface
  /// measured on the ray through it (within the view's depth range and ray length) at least
  /// truncation_m + free_margin_m deeper.
  bool observed_free = false;
  /// Some view saw the surface point closest to the point (inside its image and depth
  /// range, nothing in front of it by more than a centimetre): a field built from the views
  /// can know the distance. False where the nearest surface was never seen (a ceiling the
  /// camera never looked at): the field can only overestimate there.
  bool nearest_surface_seen = false;
};

/// Samples the truth. The sign is the vote of three rays from the point (fixed, non-axis
/// directions) among those that hit something: a first hit on the back of a triangle votes
/// inside a solid, on its front outside; inside wins only a majority of the hits (no hit at
/// all: outside). Needs every solid a closed 2-manifold with outward normals, a room seen
/// from inside being the solid around it (as the simulator's scenes are). Returns std::nullopt
/// and writes *error for invalid options or an empty box. Deterministic. Thread-safe.
std::optional<std::vector<DistanceTruthSample>> sampleDistanceTruth(
    const TriangleMeshRaycaster& truth, std::span<const DepthView> views,
    const DistanceTruthConfig& config, std::string* error);

/// The signed distance of p to the truth mesh as sampleDistanceTruth() defines it, and the
/// closest surface point when `closest` is not null. Thread-safe.
double signedDistanceToMesh(const TriangleMeshRaycaster& truth, const Eigen::Vector3d& p,
                            Eigen::Vector3d* closest = nullptr);

/// A field's answer at one sample point.
struct FieldAnswer {
  VoxelState state = VoxelState::kUnknown;
  double distance_m = 0.0;  ///< signed; ignored when unknown
};

/// The figures of a field's answers at the truth's points, voxel = the field's voxel size.
struct DistanceFieldAccuracy {
  size_t samples = 0;
  size_t answered_free = 0, answered_occupied = 0, answered_unknown = 0;
  /// |answer - truth| / voxel over the points answered free or occupied whose exact
  /// |distance| is below max_distance_m - voxel (beyond it the field clamps).
  size_t compared = 0;
  double error_median_voxels = 0.0, error_p99_voxels = 0.0, error_max_voxels = 0.0;
  /// The same over the compared points whose nearest surface some view saw.
  size_t compared_seen = 0;
  double seen_error_median_voxels = 0.0, seen_error_p99_voxels = 0.0, seen_error_max_voxels = 0.0;
  /// Points inside a solid or within one voxel of one ...
  size_t near_obstacle = 0;
  /// ... that are answered free farther than one voxel (by more than 1 % of one): a planner
  /// would fly into them.
  size_t unsafe = 0;
  /// ... and of those, the answers more than one voxel farther than the truth: not a
  /// fraction of a voxel of interpolation at a point just inside one voxel of the surface,
  /// but a surface the field misplaced or missed.
  size_t unsafe_by_a_voxel = 0;
  /// The two above at the points whose nearest surface some view saw (elsewhere no field
  /// built from the views can know the obstacle).
  size_t unsafe_seen = 0;
  size_t unsafe_seen_by_a_voxel = 0;
  /// Points the views observed as free space, and those of them answered unknown.
  size_t observed_free = 0;
  size_t observed_free_unknown = 0;
  /// Points farther than max_distance_m from every surface that are answered occupied.
  size_t far_answered_occupied = 0;
};

/// Scores answers[i] against truth[i] (same length, else std::invalid_argument).
/// Thread-safe (pure).
DistanceFieldAccuracy scoreDistanceField(std::span<const DistanceTruthSample> truth,
                                         std::span<const FieldAnswer> answers, double voxel_m,
                                         double max_distance_m);

}  // namespace cblox
