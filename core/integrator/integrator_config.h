#pragma once

#include <string>

namespace cblox {

/// How much one measurement counts in a voxel's running average.
enum class WeightModel {
  kConstant,       ///< every measurement has weight 1
  kInverseSquare,  ///< weight 1/z^2, z = measurement depth along the camera axis (metres)
};

/// How voxel colours combine measurements.
enum class ColorBlending {
  kWeightedAverage,  ///< colour averaged with the same weights as the distance
  kOverwrite,        ///< last measurement wins
  kNone,             ///< colours are not integrated
};

/// How the fast integrator remembers which voxels a frame's rays already updated.
enum class VisitedVoxelSet {
  /// One bit per voxel kept in each block, valid for one frame and guarded by the block
  /// lock the ray already holds: exact, and stays in cache. The default (BENCHMARKS.md).
  kBlockBitmap,
  /// The paper's fixed-size lock-free approximate hash set (approx_set_log2_buckets).
  kApproxHashSet,
};

/// Settings shared by the simple, fast and projective TSDF integrators.
/// All lengths in metres; defaults follow the paper's 7-Scenes set-up
/// (2 cm voxels, 4-voxel truncation).
struct IntegratorConfig {
  /// Distances beyond +-truncation are clamped; voxels further than this behind the
  /// surface are not updated. Must be >= the layer's voxel size.
  float truncation_distance_m = 0.08f;
  /// Weights saturate here so the map stays responsive to change.
  float max_weight = 10000.0f;
  /// Points closer than this to the sensor (ray length) are skipped and counted.
  float min_ray_length_m = 0.1f;
  /// Points further than this from the sensor (ray length) are skipped and counted.
  float max_ray_length_m = 5.0f;
  WeightModel weight_model = WeightModel::kInverseSquare;
  /// Linear weight drop-off behind the surface (from -voxel_size to -truncation), as in
  /// voxblox; reduces the thickening of thin objects.
  bool use_weight_dropoff = true;
  /// Ray-casting integrators: also update the free space between the sensor and the
  /// truncation band (clamped to +truncation). Off: only the band is updated.
  bool voxel_carving_enabled = true;
  /// Projective integrator: also the blocks in front of each 8x8-pixel cell's nearest
  /// measured depth, up to this depth (metres along the optical axis), so the free space the
  /// camera saw is mapped (its voxels updated to +truncation) and a planner can tell it from
  /// unknown space; 0: only the blocks near the measured surfaces. Finite, >= 0. The
  /// ray-casting integrators ignore it (voxel_carving_enabled).
  float projective_carving_depth_m = 0.0f;
  ColorBlending color_blending = ColorBlending::kWeightedAverage;
  /// Worker threads for one frame (1 = the calling thread only).
  int num_threads = 2;
  /// AVX2 where the CPU has it, with the same results bit for bit; false: one at a time.
  /// Projective: rows of voxels are updated eight at a time where the block's
  /// voxels_per_side is a multiple of 8 (ProjectiveVoxelRows). Simple and fast: points are
  /// checked and given their start cells eight at a time (RayPointScreen).
  bool vectorized = true;

  // --- fast ray-casting integrator only ---
  /// The start-voxel set has cells of voxel_size / factor: a point whose cell was already
  /// used by an earlier ray of the same frame is skipped. 1 = one ray per voxel-sized
  /// cell. voxblox's default is 2 (twice the voxel resolution); 1 casts a third of the
  /// rays and is both faster and closer to the exact surfaces and to the simple
  /// integrator: every ray first updates its band behind the point, while the free space
  /// in front is carved by the few rays that are not stopped early, so more rays bias the
  /// band towards "inside" (BENCHMARKS.md, "One start ray per voxel").
  float start_voxel_subsampling_factor = 1.0f;
  /// A ray stops after it updated more than this many consecutive voxels that other rays
  /// of the same frame had already updated.
  int max_consecutive_ray_collisions = 2;
  /// Time budget per frame in seconds; 0 = unlimited. Fast integrator: checked inside the
  /// ray loops; points are visited in an order that covers the image evenly, so a cut frame
  /// leaves a sparser, not a partial, update. Projective integrator: checked before each
  /// claim of 4 blocks; claims run in bit-reversed order, so the blocks a cut frame updates
  /// are spread over the whole image. The simple integrator ignores it.
  double max_integration_time_s = 0.0;
  VisitedVoxelSet visited_voxel_set = VisitedVoxelSet::kBlockBitmap;
  /// log2 of the bucket count of each approximate set (start set, and the visited-voxel
  /// set when it is kApproxHashSet).
  int approx_set_log2_buckets = 20;

  /// Empty when valid, otherwise a message naming the offending field. `voxel_size` is
  /// the layer's voxel size, needed to check the truncation distance.
  std::string validate(float voxel_size) const;
};

}  // namespace cblox
