#pragma once

#include <vector>

#include <Eigen/Core>

#include "test/bench/bench_frames.h"

namespace cblox::bench {

/// Integrates the frames with Open3D's ScalableTSDFVolume (legacy pipeline, RGB8 colour,
/// 16^3 volume units) using `num_threads` OpenMP threads. Times only Integrate(); the
/// conversion of our images into Open3D images happens before the clock starts.
struct Open3dResult {
  std::vector<double> frame_ms;
  size_t mesh_vertices = 0;
  std::vector<Eigen::Vector3d> mesh_positions;  ///< the extracted mesh's vertices, world frame
};
Open3dResult runOpen3dScalableTsdf(const BenchSequence& sequence, float voxel_size,
                                   float truncation, float max_depth, int num_threads);

}  // namespace cblox::bench
