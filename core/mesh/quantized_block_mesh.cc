#include "core/mesh/quantized_block_mesh.h"

#include <algorithm>
#include <cmath>

namespace cblox {

std::string QuantizedBlockMesh::validate() const {
  if (positions.size() > static_cast<size_t>(kMaxVertices)) {
    return std::to_string(positions.size()) + " vertices, more than " +
           std::to_string(kMaxVertices);
  }
  if (!colors.empty() && colors.size() != positions.size()) {
    return std::to_string(colors.size()) + " colours for " + std::to_string(positions.size()) +
           " vertices";
  }
  const auto n = static_cast<int>(positions.size());
  for (size_t t = 0; t < triangles.size(); ++t) {
    for (const int16_t v : triangles[t]) {
      if (v < 0 || v >= n) {
        return "triangle " + std::to_string(t) + " names vertex " + std::to_string(v) + " of " +
               std::to_string(n);
      }
    }
  }
  return {};
}

bool quantizeBlockMesh(const Mesh& mesh_S, const Eigen::Vector3d& block_center_S,
                       double block_size, QuantizedBlockMesh* out, std::string* error) {
  out->positions.clear();
  out->colors.clear();
  out->triangles.clear();
  if (mesh_S.numVertices() > static_cast<size_t>(QuantizedBlockMesh::kMaxVertices)) {
    if (error) {
      *error = std::to_string(mesh_S.numVertices()) + " vertices in one block, more than " +
               std::to_string(QuantizedBlockMesh::kMaxVertices);
    }
    return false;
  }
  if (std::string e = mesh_S.validate(); !e.empty()) {
    if (error) *error = e;
    return false;
  }
  const double inv_quantum = 1.0 / meshQuantum(block_size);
  out->positions.reserve(mesh_S.numVertices());
  for (const Eigen::Vector3f& v : mesh_S.vertices) {
    std::array<int16_t, 3> q;
    for (int a = 0; a < 3; ++a) {
      const double steps = std::round((static_cast<double>(v[a]) - block_center_S[a]) * inv_quantum);
      q[static_cast<size_t>(a)] = static_cast<int16_t>(std::clamp(steps, -32767.0, 32767.0));
    }
    out->positions.push_back(q);
  }
  out->colors.reserve(mesh_S.colors.size());
  for (const Color& c : mesh_S.colors) out->colors.push_back({c.r, c.g, c.b});
  out->triangles.reserve(mesh_S.numTriangles());
  for (const Eigen::Vector3i& t : mesh_S.triangles) {
    out->triangles.push_back(
        {static_cast<int16_t>(t[0]), static_cast<int16_t>(t[1]), static_cast<int16_t>(t[2])});
  }
  return true;
}

Mesh dequantizeBlockMesh(const QuantizedBlockMesh& q, const Eigen::Vector3d& block_center_S,
                         double block_size) {
  const double quantum = meshQuantum(block_size);
  Mesh mesh;
  mesh.vertices.reserve(q.positions.size());
  for (const auto& p : q.positions) {
    mesh.vertices.emplace_back(static_cast<float>(block_center_S.x() + p[0] * quantum),
                               static_cast<float>(block_center_S.y() + p[1] * quantum),
                               static_cast<float>(block_center_S.z() + p[2] * quantum));
  }
  mesh.colors.reserve(q.colors.size());
  for (const auto& c : q.colors) mesh.colors.push_back(Color{c[0], c[1], c[2]});
  mesh.triangles.reserve(q.triangles.size());
  for (const auto& t : q.triangles) mesh.triangles.emplace_back(t[0], t[1], t[2]);
  return mesh;
}

}  // namespace cblox
