#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include "core/eval/trajectory_metrics.h"
#include "core/eval/umeyama.h"
#include "core/mesh/mesh.h"
#include "core/raycast/triangle_mesh_raycaster.h"
#include "core/tsdf/layer_config.h"

namespace cblox {

/// Options of evaluateMeshAccuracy(). Plain value type.
struct MeshAccuracyConfig {
  /// Distance (metres, inclusive) within which a ground-truth surface sample counts as
  /// reconstructed (completeness) and a reconstruction vertex as accurate (precision).
  /// Finite and > 0.
  double completeness_threshold_m = 0.05;
  /// Target spacing of the ground-truth surface samples used for completeness, metres:
  /// n = ceil(area / spacing^2) samples (one per spacing x spacing square of surface), at
  /// most max_surface_samples. Finite and > 0.
  double surface_sample_spacing_m = 0.02;
  /// Upper limit of n (the effective spacing sqrt(area / n) is then wider). >= 1.
  size_t max_surface_samples = 2'000'000;
  /// Seed of the sample positions (std::mt19937_64, turned into doubles by hand, so the same
  /// mesh, options and seed give the same samples with any standard library).
  uint64_t seed = 20180701;
  /// Applied to every reconstruction vertex before anything else, p_G = T_G_R.apply(p_R)
  /// (scale * R * p + t): maps the reconstruction's frame R into the ground truth's frame G,
  /// e.g. the ATE alignment T_G_E (AteResult::alignment) when the reconstruction was built
  /// with estimated poses. std::nullopt: the reconstruction is already in G. The scale must
  /// be finite and > 0.
  std::optional<Alignment> T_G_R;
  /// Reconstruction vertices farther than this (metres) from the ground truth are outliers:
  /// counted in MeshAccuracy::outlier_vertices, excluded from MeshAccuracy::accuracy_m, their
  /// vertex_errors_m entry is +infinity. > 0; infinity (the default) keeps every vertex.
  double max_distance_m = std::numeric_limits<double>::infinity();
  /// Threads for the distance queries, in [1, 64]. The results do not depend on it.
  int num_threads = 2;

  /// Empty when valid, else a message naming the bad field. Thread-safe.
  std::string validate() const;
};

/// Accuracy and completeness of a reconstructed mesh against a ground-truth surface (the
/// metrics of the C-blox paper, plus completeness, precision and F-score at a threshold as in
/// Tanks and Temples). All distances in metres, after options.T_G_R.
///
///  - Accuracy: for every reconstruction vertex, the exact Euclidean distance to the closest
///    point of the ground-truth triangles (TriangleMeshRaycaster::closestPoint(), double
///    precision on the float vertices).
///  - Completeness: the share of ground-truth surface samples whose distance to the
///    reconstruction is <= the threshold. The samples are area-uniform and stratified: sample
///    i of n sits at the position (i + U_i) / n of the cumulative triangle area (U_i uniform
///    in [0, 1)), at a uniformly random point of that triangle. The distance is to the closest
///    point of the reconstruction's triangles; a reconstruction without triangles (a point
///    cloud) is measured to its nearest vertex instead (completeness_reference "vertices").
///  - Precision: the share of all reconstruction vertices (outliers included) with an
///    accuracy error <= the threshold. F-score: 2 P C / (P + C), 0 when both are 0.
struct MeshAccuracy {
  size_t reconstruction_vertices = 0;
  size_t reconstruction_triangles = 0;
  size_t ground_truth_triangles = 0;
  double ground_truth_area_m2 = 0.0;  ///< sum of the ground-truth triangle areas
  std::optional<Alignment> T_G_R;     ///< the alignment applied (options.T_G_R)
  double max_distance_m = std::numeric_limits<double>::infinity();

  /// Statistics of the vertex errors within max_distance_m (count = vertices - outliers).
  ErrorStatistics accuracy_m;
  size_t outlier_vertices = 0;
  /// Per reconstruction vertex, in vertex order: its accuracy error, +infinity for outliers.
  std::vector<double> vertex_errors_m;

  double completeness_threshold_m = 0.0;
  size_t ground_truth_samples = 0;
  double sample_spacing_m = 0.0;  ///< effective spacing sqrt(area / samples)
  /// "triangles" or "vertices" (point-cloud reconstruction); see the struct comment.
  std::string completeness_reference = "triangles";
  double completeness = 0.0;  ///< in [0, 1]
  double precision = 0.0;     ///< in [0, 1]
  double f_score = 0.0;       ///< in [0, 1]

  /// The result as a JSON object (keys in this order):
  ///   {"reconstruction_vertices", "reconstruction_triangles", "ground_truth_triangles",
  ///    "ground_truth_area_m2",
  ///    "alignment": {"applied", "scale", "rotation_xyzw": [4], "translation_m": [3]},
  ///    "max_distance_m" (infinity: written as null),
  ///    "accuracy": {"vertices", "outlier_vertices", "rmse_m", "mean_m", "median_m",
  ///                 "p90_m", "std_m", "min_m", "max_m"},
  ///    "completeness": {"threshold_m", "ground_truth_samples", "sample_spacing_m",
  ///                     "reference", "completeness", "precision", "f_score"}}
  /// The alignment is the identity with scale 1 when none was applied. Counts are unsigned
  /// integers; nlohmann's dump() writes doubles in the shortest form that reads back to the
  /// same double and non-finite ones as null. Per-vertex errors are not included.
  /// Thread-safe.
  nlohmann::ordered_json toJson() const;
};

/// Evaluates `reconstruction` against `ground_truth` as MeshAccuracy describes, using
/// options.num_threads threads (the raycaster's queries are thread-safe). Takes about
/// (vertices + samples) closest-point queries. Returns std::nullopt with a message when the
/// options are invalid, the reconstruction has no vertex, violates its invariants
/// (Mesh::validate) or has a non-finite vertex (before or after the alignment), or the
/// ground truth has zero surface area. Thread-safe (reads its arguments only).
std::optional<MeshAccuracy> evaluateMeshAccuracy(const TriangleMeshRaycaster& ground_truth,
                                                 const Mesh& reconstruction,
                                                 const MeshAccuracyConfig& options,
                                                 std::string* error);

/// `mesh` with every vertex mapped by alignment.apply() (computed in double, stored as
/// float) and normals rotated by its rotation; colours and triangles copied. Thread-safe
/// (pure).
Mesh alignMesh(const Mesh& mesh, const Alignment& alignment);

/// Map size of a reconstruction expressed as blocks of a block-sparse voxel grid.
///
/// Not the size of the map that produced the mesh (that is TsdfLayer::numBlocks() and
/// TsdfLayer::memoryBytes(), which the mapper reports): the number of grid blocks (edge
/// voxels_per_side * voxel_size, cells [b, b + 1) * block size in the mesh's own frame, as
/// TsdfLayer lays them out) that contain at least one mesh vertex. Marching cubes puts every
/// vertex between two observed voxels of allocated blocks, so for a mesh extracted from a
/// TSDF layer of the same voxel size and block size this is a lower bound of the layer's
/// block count: the layer also holds the blocks of the truncation band around the surface
/// and of observed free space. It makes maps of different systems comparable at one
/// resolution.
struct SurfaceBlockCount {
  /// LayerConfig::voxel_size as the double with the same shortest decimal text (0.02f gives
  /// 0.02).
  double voxel_size_m = 0.0;
  int voxels_per_side = 0;
  size_t blocks = 0;
  /// blocks * voxels_per_side^3 * sizeof(TsdfVoxel) (12 bytes): voxel payload only, without
  /// block headers or hash-map slots.
  size_t voxel_bytes = 0;
};

/// Counts the blocks of `grid` holding a vertex of `mesh` (any vertex, triangles ignored; in
/// the mesh's own frame, no alignment). Returns std::nullopt with a message when `grid` is
/// invalid (LayerConfig::validate), a vertex is not finite or lies outside the block range
/// TsdfLayer can index (|block index| >= 2^20). Block indices are computed in float exactly
/// as TsdfLayer::blockIndexFromPoint() does. Thread-safe (pure).
std::optional<SurfaceBlockCount> countSurfaceBlocks(const Mesh& mesh, const LayerConfig& grid,
                                                    std::string* error);

}  // namespace cblox
