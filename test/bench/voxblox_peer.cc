#include "test/bench/voxblox_peer.h"

#include <chrono>
#include <cmath>

#include <voxblox/core/common.h>
#include <voxblox/core/layer.h>
#include <voxblox/core/voxel.h>
#include <voxblox/integrator/tsdf_integrator.h>

#include "core/geometry/depth_to_point_cloud.h"
#include "core/geometry/pinhole_camera.h"
#include "test/bench/bench_stats.h"

namespace cblox::bench {
namespace {


// voxblox's TSDF into a cblox layer of the same voxel size and block size, voxel by voxel
// (distance, weight, colour). Both put block b at [b, b+1) * block size and voxel (i,j,k)
// at origin + (i+0.5, j+0.5, k+0.5) * voxel size; the local index is recomputed from
// voxblox's voxel centre anyway, so a different linear order could not scramble the copy.
std::shared_ptr<TsdfLayer> copyLayer(const voxblox::Layer<voxblox::TsdfVoxel>& source) {
  auto layer = std::make_shared<TsdfLayer>(
      LayerConfig{source.voxel_size(), static_cast<int>(source.voxels_per_side())});
  voxblox::BlockIndexList indices;
  source.getAllAllocatedBlocks(&indices);
  const float voxel_size_inv = 1.0f / source.voxel_size();
  for (const voxblox::BlockIndex& index : indices) {
    const voxblox::Block<voxblox::TsdfVoxel>& from = source.getBlockByIndex(index);
    Block* to = layer->allocateBlock(BlockIndex(index.x(), index.y(), index.z()));
    for (size_t i = 0; i < from.num_voxels(); ++i) {
      const voxblox::TsdfVoxel& v = from.getVoxelByLinearIndex(i);
      const Eigen::Vector3f local =
          (from.computeCoordinatesFromLinearIndex(i) - to->origin()) * voxel_size_inv;
      TsdfVoxel& w = to->voxel(GridIndex(static_cast<int>(std::floor(local.x())),
                                         static_cast<int>(std::floor(local.y())),
                                         static_cast<int>(std::floor(local.z()))));
      w.distance = v.distance;
      w.weight = v.weight;
      w.color = Color{v.color.r, v.color.g, v.color.b};
    }
  }
  return layer;
}

}  // namespace

VoxbloxResult runVoxbloxFastTsdf(const BenchSequence& sequence, float voxel_size, float truncation,
                                 float max_depth, float max_ray_length, int num_threads,
                                 int voxels_per_side, bool copy_layer) {
  // voxblox's defaults (TsdfIntegratorBase::Config, as voxblox_ros's
  // getTsdfIntegratorConfigFromRosParam leaves them): voxel carving on, allow_clear on,
  // const weight off, weight drop-off on, no sparsity compensation, max weight 10000,
  // min ray length 0.1 m, integration order "mixed", start_voxel_subsampling_factor 2,
  // max_consecutive_ray_collisions 2, clear_checks_every_n_frames 1, and
  // max_integration_time_s unlimited (float max: a benchmark must integrate every point).
  // Changed, to match the cblox fast run this is compared to:
  // - default_truncation_distance = the bench's truncation (voxblox_ros: 4 voxels, the same);
  // - max_ray_length_m = the bench's (voxblox: 5 m). Depth is cut at `max_depth` by the
  //   conversion below, but a ray to an off-axis pixel is longer than its depth; with
  //   max_ray_length_m = max_depth those points would become clearing rays in voxblox and
  //   surface points in ours, so both get the same margin (cblox's bench: 1.3 x max depth);
  // - integrator_threads = the bench's thread count (voxblox: hardware_concurrency);
  // - voxels_per_side of the layer = the cblox run's (voxblox_ros: 16).
  voxblox::TsdfIntegratorBase::Config config;
  config.default_truncation_distance = truncation;
  config.max_ray_length_m = max_ray_length;
  config.integrator_threads = static_cast<size_t>(num_threads);

  voxblox::Layer<voxblox::TsdfVoxel> layer(voxel_size, static_cast<size_t>(voxels_per_side));
  voxblox::FastTsdfIntegrator integrator(config, &layer);

  const PinholeCamera camera(sequence.intrinsics);
  DepthConversionConfig conversion;  // the bench's conversion for the cblox fast run
  conversion.min_depth_m = 0.1f;
  conversion.max_depth_m = max_depth;
  VoxbloxResult result;
  for (const BenchFrame& frame : sequence.frames) {
    // Not timed: the camera-frame cloud (as our fast integrator gets it, whose clock does
    // include this conversion), its copy into voxblox's types, and the pose.
    const auto convert_start = std::chrono::steady_clock::now();
    const PointCloud cloud = depthToPointCloud(frame.depth, camera, &frame.color, conversion);
    result.conversion_ms.push_back(msSince(convert_start));
    voxblox::Pointcloud points_C;
    voxblox::Colors colors;
    points_C.reserve(cloud.size());
    colors.reserve(cloud.size());
    for (size_t i = 0; i < cloud.size(); ++i) {
      points_C.push_back(cloud.points[i]);
      const Color& c = cloud.colors[i];
      colors.emplace_back(c.r, c.g, c.b);
    }
    const Eigen::Quaternionf q = frame.T_G_C.rotation().cast<float>().normalized();
    const voxblox::Transformation T_G_C(voxblox::Transformation::Rotation(q),
                                        frame.T_G_C.translation().cast<float>());

    const auto start = std::chrono::steady_clock::now();
    integrator.integratePointCloud(T_G_C, points_C, colors);
    result.frame_ms.push_back(msSince(start));
  }
  result.blocks = layer.getNumberOfAllocatedBlocks();
  result.layer_mib = layer.getMemorySize() / 1048576.0;
  if (copy_layer) result.layer = copyLayer(layer);
  return result;
}

}  // namespace cblox::bench
