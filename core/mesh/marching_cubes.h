#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/color.h"
#include "core/mesh/mesh.h"

namespace cblox {

/// Input of one marching-cubes cell: corner i (numbering in marching_cubes_tables.h) is at
/// positions[i] with signed distance sdf[i] (positive outside) and colour colors[i].
struct CubeCorners {
  std::array<Eigen::Vector3f, 8> positions;
  std::array<float, 8> sdf;
  std::array<Color, 8> colors;
};

/// Configuration index of a cube: bit i set when sdf[i] < 0 (a corner at exactly 0 counts
/// as outside). Thread-safe (pure).
int cubeConfiguration(const std::array<float, 8>& sdf);

/// Fraction t in (0, 1] of the zero crossing from the corner with distance `d_from` to the
/// one with `d_to`, by linear interpolation: t = d_from / (d_from - d_to). Requires the two
/// to lie on different sides (one < 0, the other >= 0), so the denominator is never 0.
/// Thread-safe (pure).
inline float zeroCrossingFraction(float d_from, float d_to) { return d_from / (d_from - d_to); }

/// Per-channel linear interpolation a + t (b - a), rounded. Thread-safe (pure).
Color lerpColor(const Color& a, const Color& b, float t);

/// Triangles of a configuration as triples of cube edge indices, ordered so that each
/// triangle is counter-clockwise seen from the positive (outside) side. Returns the number
/// of triangles written (0..5). Thread-safe (pure).
int cubeTriangles(int configuration, std::array<std::array<int, 3>, 5>* triangles);

/// Triangulates one cube and appends the result to `mesh`. Every crossed edge gets one
/// vertex at the linearly interpolated zero crossing (interpolated from the edge's lower to
/// its upper corner, so two cubes sharing an edge compute bit-identical points), shared by
/// this cube's triangles. Colours are interpolated and appended when `with_colors` (the
/// mesh's colours must then be per vertex); no normals are added. Returns the number of
/// triangles appended. Not thread-safe for `mesh`.
int meshCube(const CubeCorners& cube, bool with_colors, Mesh* mesh);

/// As meshCube, and additionally appends to `vertex_edges`, for each vertex appended to
/// `mesh`, the cube edge (0..11) it lies on, so the caller can merge vertices of edges
/// shared with neighbouring cubes. Not thread-safe for `mesh` / `vertex_edges`.
int meshCube(const CubeCorners& cube, bool with_colors, Mesh* mesh,
             std::vector<uint8_t>* vertex_edges);

}  // namespace cblox
