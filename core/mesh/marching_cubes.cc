#include "core/mesh/marching_cubes.h"

#include <algorithm>
#include <cmath>

#include "core/mesh/marching_cubes_tables.h"

namespace cblox {

int cubeConfiguration(const std::array<float, 8>& sdf) {
  int config = 0;
  for (int i = 0; i < 8; ++i) {
    if (sdf[static_cast<size_t>(i)] < 0.0f) config |= 1 << i;
  }
  return config;
}

Color lerpColor(const Color& a, const Color& b, float t) {
  const auto channel = [t](uint8_t x, uint8_t y) {
    const float v = static_cast<float>(x) + t * (static_cast<float>(y) - static_cast<float>(x));
    return static_cast<uint8_t>(std::clamp(std::lround(v), 0L, 255L));
  };
  return Color{channel(a.r, b.r), channel(a.g, b.g), channel(a.b, b.b)};
}

int cubeTriangles(int configuration, std::array<std::array<int, 3>, 5>* triangles) {
  const int8_t* row = mc::kTriangleTable[configuration & 0xff];
  int count = 0;
  for (int col = 0; col < 15 && row[col] >= 0; col += 3, ++count) {
    // The published order faces the inside; reverse it to face the positive side.
    (*triangles)[static_cast<size_t>(count)] = {row[col + 2], row[col + 1], row[col]};
  }
  return count;
}

int meshCube(const CubeCorners& cube, bool with_colors, Mesh* mesh,
             std::vector<uint8_t>* vertex_edges) {
  const int config = cubeConfiguration(cube.sdf);
  const int edges = mc::kEdgeTable[config];
  if (edges == 0) return 0;
  std::array<int, 12> vertex_of_edge;
  vertex_of_edge.fill(-1);
  for (int e = 0; e < 12; ++e) {
    if ((edges & (1 << e)) == 0) continue;
    const auto lo = static_cast<size_t>(mc::kEdgeLowerCorner[e]);
    const auto hi = static_cast<size_t>(mc::kEdgeUpperCorner[e]);
    const float t = zeroCrossingFraction(cube.sdf[lo], cube.sdf[hi]);
    vertex_of_edge[static_cast<size_t>(e)] = static_cast<int>(mesh->vertices.size());
    mesh->vertices.push_back(cube.positions[lo] + t * (cube.positions[hi] - cube.positions[lo]));
    if (with_colors) mesh->colors.push_back(lerpColor(cube.colors[lo], cube.colors[hi], t));
    if (vertex_edges != nullptr) vertex_edges->push_back(static_cast<uint8_t>(e));
  }
  std::array<std::array<int, 3>, 5> tris;
  const int n = cubeTriangles(config, &tris);
  for (int i = 0; i < n; ++i) {
    const auto& t = tris[static_cast<size_t>(i)];
    mesh->triangles.emplace_back(vertex_of_edge[static_cast<size_t>(t[0])],
                                 vertex_of_edge[static_cast<size_t>(t[1])],
                                 vertex_of_edge[static_cast<size_t>(t[2])]);
  }
  return n;
}

int meshCube(const CubeCorners& cube, bool with_colors, Mesh* mesh) {
  return meshCube(cube, with_colors, mesh, nullptr);
}

}  // namespace cblox
