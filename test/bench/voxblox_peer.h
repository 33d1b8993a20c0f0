#pragma once

#include <memory>
#include <vector>

#include "core/tsdf/tsdf_layer.h"
#include "test/bench/bench_frames.h"

namespace cblox::bench {

/// Integrates the frames with voxblox's own FastTsdfIntegrator (ethz-asl/voxblox, linked
/// from a build of its core outside this repository: see test/bench/CMakeLists.txt) using
/// `num_threads` integrator threads and blocks of `voxels_per_side`^3 voxels. Each depth
/// image becomes a camera-frame point cloud with our depthToPointCloud (min depth 0.1 m,
/// max depth `max_depth`), copied into voxblox's Pointcloud/Colors, and the pose into
/// voxblox's Transformation, all before the clock starts: only
/// FastTsdfIntegrator::integratePointCloud is timed.
struct VoxbloxResult {
  std::vector<double> frame_ms;
  /// Per frame, depthToPointCloud alone: inside our fast integrator's clock, outside
  /// voxblox's (so the comparison favours voxblox by this much).
  std::vector<double> conversion_ms;
  /// voxblox's TSDF (distance, weight, colour per voxel) copied into a cblox layer of the
  /// same voxel and block size, for the bench's mesh and accuracy code (null when
  /// copy_layer is false, as for --only's peak memory).
  std::shared_ptr<TsdfLayer> layer;
  size_t blocks = 0;
  /// voxblox's own Layer::getMemorySize() (blocks only, no hash map).
  double layer_mib = 0.0;
};
VoxbloxResult runVoxbloxFastTsdf(const BenchSequence& sequence, float voxel_size, float truncation,
                                 float max_depth, float max_ray_length, int num_threads,
                                 int voxels_per_side, bool copy_layer = true);

}  // namespace cblox::bench
