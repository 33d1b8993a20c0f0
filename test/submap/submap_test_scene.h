#pragma once

// Shared set-up for the submap tests: the analytic sphere scene (a 0.5 m sphere on a ground
// plane) rendered by a small depth camera from an orbit, integrated into submaps with the
// projective integrator. Test-only; not thread-safe.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>
#include <vector>

#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"
#include "core/integrator/integrator_config.h"
#include "core/integrator/projective_tsdf_integrator.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_integrator.h"
#include "core/submap/submap.h"
#include "core/tsdf/tsdf_layer.h"
#include "drivers/synthetic/analytic_scene.h"
#include "drivers/synthetic/scenes.h"
#include "drivers/synthetic/synthetic_frame_source.h"

namespace cblox::test {

inline constexpr float kVoxelSize = 0.02f;
inline constexpr double kMaxRange = 3.0;

inline PinholeIntrinsics smallIntrinsics() { return {150.0, 150.0, 79.5, 59.5, 160, 120}; }

/// `count` frames on a 1.6 m orbit, 0.5 m above the sphere's centre, looking slightly below
/// it (so the ground plane around the sphere is seen too).
inline std::vector<SyntheticFrame> renderOrbit(int count,
                                               PinholeIntrinsics intrinsics = smallIntrinsics()) {
  SyntheticDepthSource source(
      makeSphereScene(), intrinsics,
      makeOrbitTrajectory(Eigen::Vector3d::Zero(), 1.6, 0.5, count, Eigen::Vector3d(0, 0, -0.2)),
      10.0, kMaxRange);
  std::vector<SyntheticFrame> frames(source.size());
  for (SyntheticFrame& frame : frames) source.next(&frame);
  return frames;
}

inline IntegratorConfig integratorConfig(int num_threads = 2) {
  IntegratorConfig config;
  config.num_threads = num_threads;
  config.max_ray_length_m = static_cast<float>(kMaxRange + 0.5);
  return config;
}

/// Integrates frames [begin, end) into the submap's layer with T_M_C = T_G_M^-1 T_G_C.
inline void integrateFrames(Submap* submap, const std::vector<SyntheticFrame>& frames, size_t begin,
                            size_t end) {
  Submap::WriteLock lock = submap->lockForIntegration();
  ProjectiveTsdfIntegrator integrator(integratorConfig(), &lock.layer());
  const PinholeCamera camera(smallIntrinsics());
  for (size_t i = begin; i < end; ++i) {
    integrator.integrateDepthImage(submap->T_M_C(frames[i].T_G_C), frames[i].depth, camera,
                                   &frames[i].color);
  }
}

/// The same into a plain layer whose frame has pose T_G_L.
inline void integrateFrames(TsdfLayer* layer, const Transformationd& T_G_L,
                            const std::vector<SyntheticFrame>& frames, size_t begin, size_t end) {
  ProjectiveTsdfIntegrator integrator(integratorConfig(), layer);
  const PinholeCamera camera(smallIntrinsics());
  for (size_t i = begin; i < end; ++i) {
    integrator.integrateDepthImage((T_G_L.inverse() * frames[i].T_G_C).cast<float>(),
                                   frames[i].depth, camera, &frames[i].color);
  }
}

/// Connected marching-cubes mesh of every block, in the layer frame.
inline Mesh meshLayer(const TsdfLayer& layer) {
  MeshIntegrator mesher(layer, MeshConfig{});
  mesher.update(/*only_updated_blocks=*/false, /*clear_updated_flags=*/false);
  return mesher.extractMesh(/*connected=*/true);
}

/// RMSE (metres) of the exact signed distance of the vertices of mesh_G to the scene.
inline double vertexRmse(const Mesh& mesh_G, const AnalyticScene& scene) {
  double sum_sq = 0.0;
  for (const Eigen::Vector3f& v : mesh_G.vertices) {
    const double d = scene.signedDistance(v.cast<double>());
    sum_sq += d * d;
  }
  return mesh_G.vertices.empty() ? 0.0
                                 : std::sqrt(sum_sq / static_cast<double>(mesh_G.numVertices()));
}

/// Every voxel of the layer, blocks sorted by key: for bit-exact comparisons.
inline std::vector<std::pair<uint64_t, std::vector<TsdfVoxel>>> layerVoxels(
    const TsdfLayer& layer) {
  std::vector<std::pair<uint64_t, std::vector<TsdfVoxel>>> result;
  for (const auto& [key, block] : layer.blocks()) {
    result.emplace_back(
        key, std::vector<TsdfVoxel>(block->voxels(), block->voxels() + block->numVoxels()));
  }
  std::sort(result.begin(), result.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  return result;
}

inline bool sameVoxels(const std::vector<std::pair<uint64_t, std::vector<TsdfVoxel>>>& a,
                       const std::vector<std::pair<uint64_t, std::vector<TsdfVoxel>>>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].first != b[i].first || a[i].second.size() != b[i].second.size()) return false;
    if (std::memcmp(a[i].second.data(), b[i].second.data(),
                    a[i].second.size() * sizeof(TsdfVoxel)) != 0) {
      return false;
    }
  }
  return true;
}

}  // namespace cblox::test
