#include "core/mesh/mesh_topology.h"

#include <algorithm>
#include <cstdint>
#include <sstream>

#include "absl/container/flat_hash_map.h"

namespace cblox {
namespace {

struct EdgeUse {
  int count = 0;
  int forward = 0;  // uses as (smaller index -> larger index)
};

uint64_t edgeKey(int a, int b) {
  const auto lo = static_cast<uint64_t>(std::min(a, b));
  const auto hi = static_cast<uint64_t>(std::max(a, b));
  return (lo << 32) | hi;
}

}  // namespace

std::string MeshTopology::summary() const {
  std::ostringstream text;
  text << edges << " edges, " << boundary_edges << " boundary, " << non_manifold_edges
       << " non-manifold, " << misoriented_edges << " misoriented, " << degenerate_triangles
       << " degenerate triangles";
  return text.str();
}

MeshTopology analyzeTopology(const Mesh& mesh) {
  MeshTopology topology;
  absl::flat_hash_map<uint64_t, EdgeUse> edges;
  edges.reserve(mesh.triangles.size() * 3 / 2 + 1);
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3f& a = mesh.vertices[t[0]];
    const float area2 =
        (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).squaredNorm();
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || !(area2 > 0.0f)) {
      ++topology.degenerate_triangles;
    }
    for (int k = 0; k < 3; ++k) {
      const int from = t[k], to = t[(k + 1) % 3];
      if (from == to) continue;
      EdgeUse& use = edges[edgeKey(from, to)];
      ++use.count;
      if (from < to) ++use.forward;
    }
  }
  topology.edges = edges.size();
  for (const auto& [key, use] : edges) {
    if (use.count == 1) ++topology.boundary_edges;
    if (use.count > 2) ++topology.non_manifold_edges;
    if (use.count == 2 && use.forward != 1) ++topology.misoriented_edges;
  }
  if (topology.non_manifold_edges > 0) {
    for (size_t i = 0; i < mesh.triangles.size() && topology.first_non_manifold_triangle < 0;
         ++i) {
      const Eigen::Vector3i& t = mesh.triangles[i];
      for (int k = 0; k < 3; ++k) {
        if (t[k] == t[(k + 1) % 3]) continue;
        if (edges[edgeKey(t[k], t[(k + 1) % 3])].count > 2) {
          topology.first_non_manifold_triangle = static_cast<long>(i);
          break;
        }
      }
    }
  }
  return topology;
}

double enclosedVolume(const Mesh& mesh) {
  double volume = 0.0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[t[1]].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[t[2]].cast<double>();
    volume += a.dot(b.cross(c)) / 6.0;
  }
  return volume;
}

}  // namespace cblox
