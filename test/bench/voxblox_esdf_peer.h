#pragma once

#include <memory>

#include "core/tsdf/tsdf_layer.h"

namespace cblox::bench {

/// voxblox's own EsdfIntegrator (ethz-asl/voxblox, linked from a build of its core outside
/// this repository: see test/bench/CMakeLists.txt) on a copy of one of our TSDF layers, for
/// the distance-field bench: the same TSDF voxels, voxblox's distance field.
///
/// update() copies the blocks of `tsdf` that are new or whose Block::changeCount() moved
/// since the last call into voxblox's TSDF layer (distance and weight, flagged for the
/// ESDF), outside the clock, then times EsdfIntegrator::updateFromTsdfLayer(true): voxblox's
/// incremental update. batch() times updateFromTsdfLayerBatch() into a fresh distance layer
/// from the same copy. voxblox's settings: its defaults but max_distance_m and
/// default_distance_m (the bench's cap), min_distance_m (voxblox takes TSDF values below it
/// as the distance; it asks for the truncation or less) and full_euclidean_distance
/// (quasi-Euclidean when false, voxblox's default).
class VoxbloxEsdfPeer {
 public:
  VoxbloxEsdfPeer(const LayerConfig& geometry, float max_distance_m, float min_distance_m,
                  bool full_euclidean);
  ~VoxbloxEsdfPeer();
  VoxbloxEsdfPeer(const VoxbloxEsdfPeer&) = delete;
  VoxbloxEsdfPeer& operator=(const VoxbloxEsdfPeer&) = delete;

  /// ms of voxblox's incremental update after the copy.
  double update(const TsdfLayer& tsdf);
  /// ms of voxblox's batch update of the copied TSDF into a fresh layer (kept apart from the
  /// incremental one).
  double batch();
  /// The incremental field's distance at global voxel `index` when voxblox has observed
  /// it: false when the block is absent or the voxel unobserved.
  bool distance(const GlobalVoxelIndex& index, float* distance) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cblox::bench
