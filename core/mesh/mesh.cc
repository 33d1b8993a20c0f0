#include "core/mesh/mesh.h"

#include <sstream>

namespace cblox {

void Mesh::clear() {
  vertices.clear();
  colors.clear();
  normals.clear();
  triangles.clear();
}

void Mesh::append(const Mesh& other) {
  if (other.empty()) return;
  if (empty()) {
    *this = other;
    return;
  }
  const bool keep_colors = hasColors() && other.hasColors();
  const bool keep_normals = hasNormals() && other.hasNormals();
  const int offset = static_cast<int>(vertices.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  if (keep_colors) {
    colors.insert(colors.end(), other.colors.begin(), other.colors.end());
  } else {
    colors.clear();
  }
  if (keep_normals) {
    normals.insert(normals.end(), other.normals.begin(), other.normals.end());
  } else {
    normals.clear();
  }
  triangles.reserve(triangles.size() + other.triangles.size());
  for (const Eigen::Vector3i& t : other.triangles) {
    triangles.push_back(t + Eigen::Vector3i::Constant(offset));
  }
}

std::string Mesh::validate() const {
  std::ostringstream msg;
  if (!colors.empty() && colors.size() != vertices.size()) {
    msg << "mesh has " << colors.size() << " colours for " << vertices.size() << " vertices";
    return msg.str();
  }
  if (!normals.empty() && normals.size() != vertices.size()) {
    msg << "mesh has " << normals.size() << " normals for " << vertices.size() << " vertices";
    return msg.str();
  }
  const auto n = static_cast<long long>(vertices.size());
  for (size_t i = 0; i < triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const int v = triangles[i][k];
      if (v < 0 || v >= n) {
        msg << "triangle " << i << " has vertex index " << v << " outside [0, " << n << ")";
        return msg.str();
      }
    }
  }
  return {};
}

Mesh transformMesh(const Transformation& T_A_B, const Mesh& mesh_B) {
  Mesh mesh_A;
  mesh_A.vertices.reserve(mesh_B.vertices.size());
  for (const Eigen::Vector3f& p_B : mesh_B.vertices) mesh_A.vertices.push_back(T_A_B * p_B);
  mesh_A.normals.reserve(mesh_B.normals.size());
  for (const Eigen::Vector3f& n_B : mesh_B.normals) {
    mesh_A.normals.push_back(T_A_B.rotation() * n_B);
  }
  mesh_A.colors = mesh_B.colors;
  mesh_A.triangles = mesh_B.triangles;
  return mesh_A;
}

}  // namespace cblox
