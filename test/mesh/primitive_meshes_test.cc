#include "core/mesh/primitive_meshes.h"

#include <cmath>

#include <gtest/gtest.h>

#include "core/mesh/mesh_topology.h"

namespace cblox {
namespace {

constexpr double kPi = 3.14159265358979323846;
const Color kRed{255, 0, 0};

TEST(PrimitiveMeshesTest, BoxIsClosedOutwardAndHasExactVolume) {
  Mesh mesh;
  appendBox(&mesh, Eigen::AlignedBox3f(Eigen::Vector3f(-1, 0, 2), Eigen::Vector3f(1, 3, 2.5f)),
            kRed);
  EXPECT_EQ(mesh.numVertices(), 8u);
  EXPECT_EQ(mesh.numTriangles(), 12u);
  EXPECT_TRUE(mesh.validate().empty());
  const MeshTopology topology = analyzeTopology(mesh);
  EXPECT_TRUE(topology.closed()) << topology.summary();
  EXPECT_EQ(topology.edges, 18u);
  EXPECT_NEAR(enclosedVolume(mesh), 2.0 * 3.0 * 0.5, 1e-6);

  Mesh inward;
  appendBox(&inward, Eigen::AlignedBox3f(Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 1, 1)),
            kRed, /*inward=*/true);
  EXPECT_TRUE(analyzeTopology(inward).closed());
  EXPECT_NEAR(enclosedVolume(inward), -1.0, 1e-6);
}

TEST(PrimitiveMeshesTest, OrientedBoxVolumeIsInvariantUnderRotation) {
  Mesh mesh;
  const Transformation T(Eigen::Quaternionf(Eigen::AngleAxisf(0.7f, Eigen::Vector3f(1, 2, 3).normalized())),
                         Eigen::Vector3f(5, -2, 1));
  appendOrientedBox(&mesh, T, Eigen::Vector3f(0.5f, 1.0f, 1.5f), kRed);
  EXPECT_TRUE(analyzeTopology(mesh).closed());
  EXPECT_NEAR(enclosedVolume(mesh), 1.0 * 2.0 * 3.0, 1e-4);
}

TEST(PrimitiveMeshesTest, CylinderConeSphereAndRingAreClosedWithPolygonVolumes) {
  const int n = 24;
  const double polygon_area = 0.5 * n * std::sin(2.0 * kPi / n);  // of a unit-radius n-gon
  Mesh cylinder;
  appendCylinder(&cylinder, Eigen::Vector3f(1, 1, 0), Eigen::Vector3f(0, 0, 2), 0.5f, n, kRed);
  EXPECT_TRUE(analyzeTopology(cylinder).closed()) << analyzeTopology(cylinder).summary();
  EXPECT_NEAR(enclosedVolume(cylinder), polygon_area * 0.25 * 2.0, 1e-5);

  Mesh cone;
  appendCone(&cone, Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(0, 3, 0), 1.0f, n, kRed);
  EXPECT_TRUE(analyzeTopology(cone).closed());
  EXPECT_NEAR(enclosedVolume(cone), polygon_area * 3.0 / 3.0, 1e-5);

  Mesh sphere;
  appendSphere(&sphere, Eigen::Vector3f(0, 0, 1), 2.0f, 32, 64, kRed);
  EXPECT_TRUE(analyzeTopology(sphere).closed());
  const double true_volume = 4.0 / 3.0 * kPi * 8.0;
  EXPECT_NEAR(enclosedVolume(sphere), true_volume, 0.01 * true_volume);
  EXPECT_LT(enclosedVolume(sphere), true_volume);  // inscribed polyhedron

  Mesh ring;
  appendPipeBend(&ring, Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitX(),
                 Eigen::Vector3f::UnitY(), 2.0f, 0.25f, 7.0f, 48, 16, kRed);
  EXPECT_TRUE(analyzeTopology(ring).closed());
  // Pappus (2 pi R * pi r^2) times each polygon's area factor n sin(2 pi / n) / (2 pi).
  auto polygon_factor = [](int sides) { return sides * std::sin(2 * kPi / sides) / (2 * kPi); };
  const double ring_volume = 2 * kPi * 2.0 * kPi * 0.0625 * polygon_factor(16) * polygon_factor(48);
  EXPECT_NEAR(enclosedVolume(ring), ring_volume, 1e-3 * ring_volume);

  Mesh elbow;
  appendPipeBend(&elbow, Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitX(),
                 Eigen::Vector3f::UnitZ(), 1.0f, 0.2f, static_cast<float>(kPi / 2), 8, 12, kRed);
  EXPECT_TRUE(analyzeTopology(elbow).closed()) << analyzeTopology(elbow).summary();
  EXPECT_GT(enclosedVolume(elbow), 0.0);
}

TEST(PrimitiveMeshesTest, QuadGridHasABoundaryAndFacesItsNormal) {
  Mesh quad;
  appendQuad(&quad, Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(2, 0, 0), Eigen::Vector3f(0, 1, 0),
             kRed, 4, 2);
  EXPECT_EQ(quad.numVertices(), 15u);
  EXPECT_EQ(quad.numTriangles(), 16u);
  const MeshTopology topology = analyzeTopology(quad);
  EXPECT_TRUE(topology.manifold());
  EXPECT_EQ(topology.boundary_edges, 12u);
  EXPECT_EQ(topology.misoriented_edges, 0u);
  for (const Eigen::Vector3i& t : quad.triangles) {
    const Eigen::Vector3f n =
        (quad.vertices[t[1]] - quad.vertices[t[0]]).cross(quad.vertices[t[2]] - quad.vertices[t[0]]);
    EXPECT_GT(n.z(), 0.0f);
  }
}

TEST(MeshTopologyTest, FindsNonManifoldMisorientedAndDegenerate) {
  Mesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {2, 0, 0}};
  // Three triangles on edge (0, 1): non-manifold; the first one is triangle 0.
  mesh.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {0, 1, 5}};
  MeshTopology topology = analyzeTopology(mesh);
  EXPECT_EQ(topology.non_manifold_edges, 1u);
  EXPECT_EQ(topology.first_non_manifold_triangle, 0);
  EXPECT_FALSE(topology.manifold());
  EXPECT_EQ(topology.degenerate_triangles, 1u);  // (0, 1, 5) is collinear

  mesh.triangles = {{0, 1, 2}, {0, 1, 3}};  // both traverse 0 -> 1
  topology = analyzeTopology(mesh);
  EXPECT_EQ(topology.misoriented_edges, 1u);
  EXPECT_TRUE(topology.manifold());
  EXPECT_FALSE(topology.closed());
}

TEST(PrimitiveMeshesTest, RejectsBadArguments) {
  Mesh mesh;
  EXPECT_THROW(appendCylinder(&mesh, Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitZ(), 1, 2, kRed),
               std::invalid_argument);
  Mesh uncoloured;
  uncoloured.vertices.push_back(Eigen::Vector3f::Zero());
  EXPECT_THROW(appendBox(&uncoloured, Eigen::AlignedBox3f(Eigen::Vector3f::Zero(), Eigen::Vector3f::Ones()), kRed),
               std::invalid_argument);
}

}  // namespace
}  // namespace cblox
