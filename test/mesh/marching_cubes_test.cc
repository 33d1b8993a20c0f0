#include "core/mesh/marching_cubes.h"

#include <algorithm>
#include <map>
#include <set>
#include <utility>

#include <gtest/gtest.h>

#include "core/mesh/marching_cubes_tables.h"

namespace cblox {
namespace {

bool inside(int config, int corner) { return (config >> corner) & 1; }

// The edge table must say exactly which edges join an inside and an outside corner.
TEST(MarchingCubesTables, EdgeTableMatchesCornerSigns) {
  for (int config = 0; config < 256; ++config) {
    for (int e = 0; e < 12; ++e) {
      const bool crossed =
          inside(config, mc::kEdgeCorners[e][0]) != inside(config, mc::kEdgeCorners[e][1]);
      EXPECT_EQ(crossed, ((mc::kEdgeTable[config] >> e) & 1) != 0)
          << "config " << config << " edge " << e;
    }
  }
}

TEST(MarchingCubesTables, EdgeNumberingIsConsistent) {
  for (int e = 0; e < 12; ++e) {
    const int lo = mc::kEdgeLowerCorner[e];
    const int hi = mc::kEdgeUpperCorner[e];
    const int a = mc::kEdgeAxis[e];
    // Same corner pair as kEdgeCorners, ordered along +axis.
    EXPECT_TRUE((lo == mc::kEdgeCorners[e][0] && hi == mc::kEdgeCorners[e][1]) ||
                (lo == mc::kEdgeCorners[e][1] && hi == mc::kEdgeCorners[e][0]));
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(mc::kCornerOffsets[hi][k] - mc::kCornerOffsets[lo][k], k == a ? 1 : 0)
          << "edge " << e;
    }
  }
}

// Cube faces as sets of the edges that bound them.
const std::set<int> kFaceEdges[6] = {{0, 1, 2, 3},   {4, 5, 6, 7},  {0, 4, 8, 9},
                                     {2, 6, 10, 11}, {3, 7, 8, 11}, {1, 5, 9, 10}};

bool onCommonFace(int e0, int e1) {
  for (const auto& face : kFaceEdges) {
    if (face.count(e0) && face.count(e1)) return true;
  }
  return false;
}

// Per configuration: triangles use exactly the crossed edges, form a consistently oriented
// patch (an interior edge is used once in each direction), and the patch boundary runs on
// the cube faces (so that neighbouring cubes can close it).
TEST(MarchingCubesTables, TrianglePatchesAreConsistent) {
  for (int config = 0; config < 256; ++config) {
    std::array<std::array<int, 3>, 5> tris;
    const int n = cubeTriangles(config, &tris);
    std::set<int> used;
    std::map<std::pair<int, int>, int> directed;
    for (int i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) {
        const int a = tris[static_cast<size_t>(i)][static_cast<size_t>(k)];
        const int b = tris[static_cast<size_t>(i)][static_cast<size_t>((k + 1) % 3)];
        ASSERT_TRUE((mc::kEdgeTable[config] >> a) & 1) << "config " << config;
        used.insert(a);
        ++directed[{a, b}];
      }
    }
    for (int e = 0; e < 12; ++e) {
      EXPECT_EQ(used.count(e) == 1, ((mc::kEdgeTable[config] >> e) & 1) != 0)
          << "config " << config << " edge " << e;
    }
    for (const auto& [edge, count] : directed) {
      EXPECT_EQ(count, 1) << "config " << config;
      if (directed.count({edge.second, edge.first}) == 0) {
        EXPECT_TRUE(onCommonFace(edge.first, edge.second))
            << "config " << config << ": boundary edge " << edge.first << "-" << edge.second
            << " crosses the cube";
      }
    }
  }
}

CubeCorners unitCube(const std::array<float, 8>& sdf) {
  CubeCorners cube;
  for (int c = 0; c < 8; ++c) {
    cube.positions[static_cast<size_t>(c)] = Eigen::Vector3f(
        static_cast<float>(mc::kCornerOffsets[c][0]), static_cast<float>(mc::kCornerOffsets[c][1]),
        static_cast<float>(mc::kCornerOffsets[c][2]));
    cube.colors[static_cast<size_t>(c)] = Color{};
  }
  cube.sdf = sdf;
  return cube;
}

TEST(MarchingCubes, SingleInsideCornerGivesOneOutwardTriangle) {
  // Corner 0 inside at -1, the rest outside at +3: crossings at t = 1/4 on edges 0, 3, 8.
  CubeCorners cube = unitCube({-1.0f, 3.0f, 3.0f, 3.0f, 3.0f, 3.0f, 3.0f, 3.0f});
  cube.colors[0] = Color{0, 0, 0};
  cube.colors[1] = Color{200, 100, 40};
  Mesh mesh;
  std::vector<uint8_t> edges;
  ASSERT_EQ(meshCube(cube, /*with_colors=*/true, &mesh, &edges), 1);
  ASSERT_EQ(mesh.numVertices(), 3u);
  ASSERT_EQ(mesh.numTriangles(), 1u);
  EXPECT_EQ(edges, (std::vector<uint8_t>{0, 3, 8}));  // ascending edge order
  EXPECT_TRUE(mesh.vertices[0].isApprox(Eigen::Vector3f(0.25f, 0, 0)));
  EXPECT_TRUE(mesh.vertices[1].isApprox(Eigen::Vector3f(0, 0.25f, 0)));
  EXPECT_TRUE(mesh.vertices[2].isApprox(Eigen::Vector3f(0, 0, 0.25f)));
  EXPECT_EQ(mesh.colors[0], (Color{50, 25, 10}));  // a quarter of the way to corner 1
  EXPECT_EQ(mesh.colors[1], (Color{0, 0, 0}));
  const Eigen::Vector3i& t = mesh.triangles[0];
  const Eigen::Vector3f normal =
      (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
  // Outward = away from the inside corner 0.
  EXPECT_GT(normal.dot(Eigen::Vector3f(1, 1, 1)), 0.0f);
  EXPECT_TRUE(mesh.normals.empty());
}

TEST(MarchingCubes, EmptyAndFullCubesGiveNothing) {
  Mesh mesh;
  EXPECT_EQ(meshCube(unitCube({1, 1, 1, 1, 1, 1, 1, 1}), false, &mesh), 0);
  EXPECT_EQ(meshCube(unitCube({-1, -1, -1, -1, -1, -1, -1, -1}), false, &mesh), 0);
  // A corner at exactly 0 counts as outside: no crossing.
  EXPECT_EQ(meshCube(unitCube({0, 1, 1, 1, 1, 1, 1, 1}), false, &mesh), 0);
  EXPECT_TRUE(mesh.empty());
}

TEST(MarchingCubes, HalfSpaceZIsExactAndFacesUp) {
  // sdf = z - 0.3: a horizontal plane, outside above.
  std::array<float, 8> sdf;
  for (int c = 0; c < 8; ++c) sdf[static_cast<size_t>(c)] = mc::kCornerOffsets[c][2] - 0.3f;
  Mesh mesh;
  ASSERT_EQ(meshCube(unitCube(sdf), false, &mesh), 2);
  for (const auto& v : mesh.vertices) EXPECT_NEAR(v.z(), 0.3f, 1e-7f);
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f n = (mesh.vertices[t[1]] - mesh.vertices[t[0]])
                                  .cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
    EXPECT_GT(n.z(), 0.0f);
  }
}

TEST(MarchingCubes, SharedEdgeGivesBitIdenticalVertexFromBothCubes) {
  // Edge 0 of cube B (x from 1 to 2 at y=0) is edge 2 of cube A below it in y... use two
  // cubes side by side in y: cube A at y in [-1, 0], cube B at y in [0, 1]. Their shared
  // edge (y = 0, z = 0, x in [0,1]) is edge 2 of A (3 -> 2, i.e. traversed along -x in the
  // published numbering) and edge 0 of B.
  const float d_lo = -0.37f, d_hi = 0.91f;  // values at x = 0 and x = 1 on the shared edge
  CubeCorners a = unitCube({1, 1, d_hi, d_lo, 1, 1, 1, 1});
  CubeCorners b = unitCube({d_lo, d_hi, 1, 1, 1, 1, 1, 1});
  for (auto& p : a.positions) p.y() -= 1.0f;
  Mesh ma, mb;
  std::vector<uint8_t> ea, eb;
  meshCube(a, false, &ma, &ea);
  meshCube(b, false, &mb, &eb);
  const auto find = [](const std::vector<uint8_t>& edges, int e) {
    return static_cast<size_t>(std::find(edges.begin(), edges.end(), e) - edges.begin());
  };
  const size_t ia = find(ea, 2), ib = find(eb, 0);
  ASSERT_LT(ia, ea.size());
  ASSERT_LT(ib, eb.size());
  EXPECT_EQ(ma.vertices[ia], mb.vertices[ib]);  // exact, not approximate
}

}  // namespace
}  // namespace cblox
