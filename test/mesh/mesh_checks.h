#pragma once

// Test helpers: analytic SDF scenes written straight into a TsdfLayer, and mesh topology
// checks. Test-only; not thread-safe.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "core/mesh/mesh.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox::test {

/// Allocates every block overlapping [lo, hi] and sets each voxel whose |sdf(centre)| <=
/// truncation to (sdf, weight, colour(centre)); others keep weight 0.
inline void fillLayer(TsdfLayer* layer, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                      float truncation, const std::function<float(const Eigen::Vector3f&)>& sdf,
                      float weight = 1.0f,
                      const std::function<Color(const Eigen::Vector3f&)>& color = nullptr) {
  const BlockIndex b_lo = layer->blockIndexFromPoint(lo);
  const BlockIndex b_hi = layer->blockIndexFromPoint(hi);
  for (int z = b_lo.z(); z <= b_hi.z(); ++z) {
    for (int y = b_lo.y(); y <= b_hi.y(); ++y) {
      for (int x = b_lo.x(); x <= b_hi.x(); ++x) {
        Block* block = layer->allocateBlock(BlockIndex(x, y, z));
        for (int i = 0; i < block->numVoxels(); ++i) {
          // From the global index, so the value does not depend on the block size.
          const Eigen::Vector3f c = layer->globalVoxelCenter(
              block->index() * block->voxelsPerSide() + block->localIndex(i));
          const float d = sdf(c);
          TsdfVoxel& v = block->voxel(i);
          if (std::abs(d) <= truncation) {
            v.distance = d;
            v.weight = weight;
            if (color) v.color = color(c);
          } else {
            v = TsdfVoxel{};
          }
        }
        block->setUpdated(true);
      }
    }
  }
}

struct Topology {
  size_t num_edges = 0;
  size_t boundary_edges = 0;        // used by one triangle
  size_t non_manifold_edges = 0;    // used by more than two triangles
  size_t misoriented_edges = 0;     // a directed edge used twice (neighbours disagree)
  size_t degenerate_triangles = 0;  // repeated vertex index
};

/// Edge statistics of an indexed mesh.
inline Topology topology(const Mesh& mesh) {
  Topology t;
  std::map<std::pair<int, int>, std::array<int, 2>> edges;  // undirected -> (count a<b, count a>b)
  for (const Eigen::Vector3i& tri : mesh.triangles) {
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) ++t.degenerate_triangles;
    for (int k = 0; k < 3; ++k) {
      const int a = tri[k];
      const int b = tri[(k + 1) % 3];
      auto& e = edges[{std::min(a, b), std::max(a, b)}];
      ++e[a < b ? 0 : 1];
    }
  }
  t.num_edges = edges.size();
  for (const auto& [key, count] : edges) {
    const int total = count[0] + count[1];
    if (total == 1) ++t.boundary_edges;
    if (total > 2) ++t.non_manifold_edges;
    if (count[0] > 1 || count[1] > 1) ++t.misoriented_edges;
  }
  return t;
}

/// Signed volume enclosed by a closed, outward-oriented mesh (divergence theorem).
inline double signedVolume(const Mesh& mesh) {
  double volume = 0.0;
  for (const Eigen::Vector3i& tri : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[static_cast<size_t>(tri[0])].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[static_cast<size_t>(tri[1])].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[static_cast<size_t>(tri[2])].cast<double>();
    volume += a.dot(b.cross(c)) / 6.0;
  }
  return volume;
}

}  // namespace cblox::test
