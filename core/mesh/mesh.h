#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/color.h"
#include "core/geometry/se3.h"

namespace cblox {

/// An indexed triangle mesh (also used for coloured point clouds: no triangles).
///
/// Invariants (checked by validate()): `colors` and `normals` are each either empty or hold
/// one entry per vertex; every triangle index is in [0, numVertices()). Triangles are
/// counter-clockwise seen from the outside, i.e. from the positive-SDF side, so
/// (v1 - v0) x (v2 - v0) points out of the surface.
///
/// Value type: const methods may run concurrently; mutation needs external synchronisation.
struct Mesh {
  std::vector<Eigen::Vector3f> vertices;   ///< metres, in the mesh's frame
  std::vector<Color> colors;               ///< empty or one per vertex
  std::vector<Eigen::Vector3f> normals;    ///< empty or one unit vector per vertex
  std::vector<Eigen::Vector3i> triangles;  ///< vertex indices, CCW seen from outside

  size_t numVertices() const { return vertices.size(); }
  size_t numTriangles() const { return triangles.size(); }
  /// True when there are neither vertices nor triangles.
  bool empty() const { return vertices.empty() && triangles.empty(); }
  bool hasColors() const { return !colors.empty(); }
  bool hasNormals() const { return !normals.empty(); }
  void clear();

  /// Appends `other`, offsetting its triangle indices. An attribute (colours, normals) is
  /// kept only when every non-empty mesh involved has it: appending a mesh without colours
  /// to a non-empty mesh with colours drops the colours (appending to an empty mesh copies
  /// `other` as is). Not thread-safe for `this`.
  void append(const Mesh& other);

  /// Empty when the invariants hold, otherwise a message naming the first violation.
  /// Thread-safe.
  std::string validate() const;
};

/// Returns mesh_B expressed in frame A: vertices are mapped by T_A_B, normals rotated;
/// colours and triangles are copied. Thread-safe (pure).
Mesh transformMesh(const Transformation& T_A_B, const Mesh& mesh_B);

}  // namespace cblox
