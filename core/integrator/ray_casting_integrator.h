#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/geometry/point_cloud.h"
#include "core/geometry/se3.h"
#include "core/integrator/approx_hash_set.h"
#include "core/integrator/integration_stats.h"
#include "core/integrator/integrator_config.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox {

/// Integrates point clouds with a sensor origin into a TSDF layer by casting one ray per
/// point from one truncation distance behind the point back towards the sensor (to the
/// sensor when voxel carving is on, else to one truncation in front of the point) and
/// updating every voxel the ray crosses with the distance along the ray.
///
/// Two modes share this engine (SimpleTsdfIntegrator and FastTsdfIntegrator below):
/// - kSimple: every ray, every voxel: the accuracy reference.
/// - kFast: the paper's integrator. A point is skipped when its cell of the start-voxel
///   set (cell = voxel_size / start_voxel_subsampling_factor) was used earlier in the
///   frame (a lock-free ApproxHashSet cleared per frame in O(1), keyed so that
///   neighbouring cells share cache lines); a ray stops after more than
///   max_consecutive_ray_collisions consecutive voxels already updated this frame
///   (the visited-voxel set: per-block bitmaps by default, or the paper's ApproxHashSet,
///   see VisitedVoxelSet); the max_integration_time_s budget is checked inside the loops.
///
/// Point order: the cloud is cut into runs of kPointsPerChunk consecutive points (a row
/// segment of a depth image) and the runs are visited in evenCoverageOrder, so a frame
/// cut short by the budget still covers the whole image, while the points of one run are
/// neighbours and keep the hash sets and blocks in cache. Threads claim runs. A run's
/// points are first checked and given their start cells together (RayPointScreen, eight at
/// a time on AVX2).
///
/// Allocation never happens while threads walk rays: a ray that enters a missing block
/// is parked (its traversal state kept); after the parallel pass the missing blocks are
/// allocated single-threaded and the parked rays resume in parallel, repeated until no
/// ray is parked. In a mapped area almost no ray is parked. A ray looks the hash map up
/// only when it crosses into another block, and holds that block's spin lock while it
/// updates the block's voxels. Blocks allocated for rays that then updated nothing are
/// removed again, so the layer never keeps empty blocks from a frame.
///
/// Thread safety: one integratePointCloud call at a time per integrator, and nothing
/// else may touch the layer during that call. Internally uses config.num_threads threads.
class RayCastingIntegrator {
 public:
  enum class Mode { kSimple, kFast };
  static constexpr size_t kPointsPerChunk = 64;

  /// Throws std::invalid_argument naming the invalid field, or if layer is null.
  RayCastingIntegrator(Mode mode, const IntegratorConfig& config, TsdfLayer* layer);
  virtual ~RayCastingIntegrator();

  /// `cloud_C` holds points in the sensor frame C (sensor at the origin); `T_G_C` places
  /// the sensor in the layer frame. Invalid points (non-finite) and points outside
  /// [min_ray_length, max_ray_length] are skipped and counted.
  IntegrationStats integratePointCloud(const Transformation& T_G_C, const PointCloud& cloud_C);

  const IntegratorConfig& config() const { return config_; }
  Mode mode() const { return mode_; }

 private:
  struct Frame;
  struct ParkedRay;
  struct ThreadState;
  struct StartCell;
  void castChunks(Frame& frame, ThreadState* state);
  void resumeParked(Frame& frame, const std::vector<ParkedRay>& parked, ThreadState* state);
  // Walks the ray of point `index`: a new one when `resume` is null, else the parked one.
  void walkRay(Frame& frame, uint32_t index, const ParkedRay* resume, ThreadState* state);

  Mode mode_;
  IntegratorConfig config_;
  TsdfLayer* layer_;
  std::unique_ptr<ApproxHashSet> start_voxel_set_;
  std::unique_ptr<ApproxHashSet> visited_voxel_set_;
  std::vector<uint32_t> chunk_order_;
};

/// Every ray, every voxel (the accuracy reference). See RayCastingIntegrator.
class SimpleTsdfIntegrator : public RayCastingIntegrator {
 public:
  SimpleTsdfIntegrator(const IntegratorConfig& config, TsdfLayer* layer)
      : RayCastingIntegrator(Mode::kSimple, config, layer) {}
};

/// The paper's fast, time-budgeted integrator. See RayCastingIntegrator.
class FastTsdfIntegrator : public RayCastingIntegrator {
 public:
  FastTsdfIntegrator(const IntegratorConfig& config, TsdfLayer* layer)
      : RayCastingIntegrator(Mode::kFast, config, layer) {}
};

}  // namespace cblox
