#pragma once

#include <cstddef>
#include <string>

#include "core/mesh/mesh.h"

namespace cblox {

/// Edge and triangle statistics of an indexed triangle mesh (edges are undirected vertex-index
/// pairs; coincident vertices with different indices are different vertices).
struct MeshTopology {
  size_t edges = 0;
  size_t boundary_edges = 0;       ///< edges of exactly one triangle
  size_t non_manifold_edges = 0;   ///< edges of three or more triangles
  size_t misoriented_edges = 0;    ///< two-triangle edges traversed the same way by both
  size_t degenerate_triangles = 0; ///< a repeated index or zero area
  /// Index of the first triangle that has a non-manifold edge, or -1.
  long first_non_manifold_triangle = -1;

  /// Every edge has exactly two consistently oriented triangles.
  bool closed() const {
    return boundary_edges == 0 && non_manifold_edges == 0 && misoriented_edges == 0;
  }
  /// No edge has more than two triangles (boundaries are allowed).
  bool manifold() const { return non_manifold_edges == 0; }

  /// One line, e.g. "1200 edges, 0 boundary, 0 non-manifold, 0 misoriented, 0 degenerate".
  std::string summary() const;
};

/// Counts the mesh's edges by the number of triangles that use them. The mesh must satisfy
/// Mesh::validate(). O(triangles) time and memory. Thread-safe (pure).
MeshTopology analyzeTopology(const Mesh& mesh);

/// Signed volume enclosed by a closed mesh (divergence theorem; positive when triangles face
/// outwards), in cubic metres. Meaningless for open meshes. Thread-safe (pure).
double enclosedVolume(const Mesh& mesh);

}  // namespace cblox
