#pragma once

// The settings the integrator benchmarks share (cblox-bench-integrators on 7-Scenes,
// cblox-bench-exact-surfaces on the analytic room), so that their figures compare.

#include "core/integrator/integrator_config.h"

namespace cblox::bench {

inline constexpr float kVoxelSize = 0.02f;
inline constexpr float kTruncation = 4 * kVoxelSize;
inline constexpr float kMaxDepth = 4.0f;
// Depth is cut at kMaxDepth (the point cloud conversion, the depth images, Open3D's
// depth_trunc); the rays to off-axis pixels are longer than their depth, so the ray-length
// limit keeps a margin (ours and voxblox's).
inline constexpr float kMaxRayLength = kMaxDepth * 1.3f;

// Exit statuses of a run whose peer is not built.
inline constexpr int kExitNoOpen3d = 3;
inline constexpr int kExitNoVoxblox = 4;
inline constexpr int kExitNoPeers = 5;

/// Our integrators' settings in the benchmarks: the defaults but for the above.
inline IntegratorConfig benchIntegratorConfig(int num_threads) {
  IntegratorConfig config;
  config.truncation_distance_m = kTruncation;
  config.max_ray_length_m = kMaxRayLength;
  config.num_threads = num_threads;
  return config;
}

}  // namespace cblox::bench
