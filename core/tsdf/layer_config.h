#pragma once

#include <string>

namespace cblox {

/// Geometry of a sparse voxel layer.
struct LayerConfig {
  /// Edge length of one voxel, metres. Must be finite and > 0.
  float voxel_size = 0.02f;
  /// Voxels along one edge of a block; a power of two in [2, 64]. 8 is the measured
  /// default (see BENCHMARKS.md, "block size").
  int voxels_per_side = 8;

  /// Empty when valid, otherwise a message naming the offending field.
  std::string validate() const;
};

}  // namespace cblox
