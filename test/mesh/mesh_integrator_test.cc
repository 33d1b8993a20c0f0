#include "core/mesh/mesh_integrator.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <set>
#include <stdexcept>

#include <gtest/gtest.h>

#include "test/mesh/mesh_checks.h"

namespace cblox {
namespace {

constexpr float kVoxel = 0.02f;
constexpr float kTruncation = 0.08f;
constexpr float kRadius = 0.3f;
const Eigen::Vector3f kCentre(0.0137f, -0.0071f, 0.0213f);  // not grid-aligned

float sphereSdf(const Eigen::Vector3f& p) { return (p - kCentre).norm() - kRadius; }

Color positionColor(const Eigen::Vector3f& p) {
  const auto c = [](float v) {
    return static_cast<uint8_t>(std::clamp(128.0f + 300.0f * v, 0.0f, 255.0f));
  };
  return Color{c(p.x()), c(p.y()), c(p.z())};
}

std::unique_ptr<TsdfLayer> sphereLayer(int voxels_per_side) {
  auto layer = std::make_unique<TsdfLayer>(LayerConfig{kVoxel, voxels_per_side});
  const Eigen::Vector3f margin = Eigen::Vector3f::Constant(kRadius + 0.1f);
  test::fillLayer(layer.get(), kCentre - margin, kCentre + margin, kTruncation, sphereSdf, 1.0f,
                  positionColor);
  return layer;
}

// Angle between two directions in degrees, accurate near 0 (unlike acos of a float dot).
double angleDegrees(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  const Eigen::Vector3d ad = a.cast<double>(), bd = b.cast<double>();
  return std::atan2(ad.cross(bd).norm(), ad.dot(bd)) * 180.0 / std::numbers::pi;
}

void expectIdentical(const Mesh& a, const Mesh& b) {
  ASSERT_EQ(a.numVertices(), b.numVertices());
  ASSERT_EQ(a.numTriangles(), b.numTriangles());
  EXPECT_TRUE(a.vertices == b.vertices);
  EXPECT_TRUE(a.normals == b.normals);
  EXPECT_TRUE(a.colors == b.colors);
  EXPECT_TRUE(a.triangles == b.triangles);
}

class MeshIntegratorBlockSize : public ::testing::TestWithParam<int> {};

// The measured accuracy of linear zero-crossing interpolation on an exact sphere SDF
// (r = 15 voxels): the SDF is convex along an edge, so the crossing is off by at most
// ~h^2 / (8 r) = 0.0083 voxel; the bound below leaves room for float rounding only.
constexpr float kSphereVertexBoundVoxels = 0.01f;
// Normals from central differences, interpolated along the edge.
constexpr float kSphereNormalBoundDegrees = 0.5f;

TEST_P(MeshIntegratorBlockSize, SphereIsAccurateWatertightAndOutward) {
  const auto layer = sphereLayer(GetParam());
  MeshIntegrator mesher(*layer, MeshConfig{});
  EXPECT_EQ(mesher.update(), layer->numBlocks());
  const Mesh mesh = mesher.extractMesh(/*connected=*/true);
  ASSERT_GT(mesh.numTriangles(), 1000u);
  ASSERT_EQ(mesh.validate(), "");
  ASSERT_EQ(mesh.normals.size(), mesh.numVertices());
  ASSERT_EQ(mesh.colors.size(), mesh.numVertices());

  // The surface spans many blocks.
  size_t non_empty = 0;
  for (const auto& [key, block_mesh] : mesher.blockMeshes()) non_empty += !block_mesh.empty();
  EXPECT_GE(non_empty, 8u);

  float max_error = 0.0f;
  double max_angle = 0.0;
  for (size_t i = 0; i < mesh.numVertices(); ++i) {
    const Eigen::Vector3f r = mesh.vertices[i] - kCentre;
    max_error = std::max(max_error, std::abs(r.norm() - kRadius));
    max_angle = std::max(max_angle, angleDegrees(mesh.normals[i], r));
    EXPECT_NEAR(mesh.normals[i].norm(), 1.0f, 1e-5f);
  }
  std::printf(
      "vps %d: %zu vertices, %zu triangles, max vertex error %.5f voxel, max normal "
      "error %.4f deg\n",
      GetParam(), mesh.numVertices(), mesh.numTriangles(), max_error / kVoxel, max_angle);
  EXPECT_LE(max_error, kSphereVertexBoundVoxels * kVoxel);
  EXPECT_LE(max_angle, kSphereNormalBoundDegrees);

  // Watertight, consistently oriented, genus 0 — across all block borders.
  const test::Topology topo = test::topology(mesh);
  EXPECT_EQ(topo.boundary_edges, 0u);
  EXPECT_EQ(topo.non_manifold_edges, 0u);
  EXPECT_EQ(topo.misoriented_edges, 0u);
  EXPECT_EQ(topo.degenerate_triangles, 0u);
  const long long euler = static_cast<long long>(mesh.numVertices()) -
                          static_cast<long long>(topo.num_edges) +
                          static_cast<long long>(mesh.numTriangles());
  EXPECT_EQ(euler, 2);

  // Every triangle faces outward.
  size_t inward = 0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3f& a = mesh.vertices[static_cast<size_t>(t[0])];
    const Eigen::Vector3f& b = mesh.vertices[static_cast<size_t>(t[1])];
    const Eigen::Vector3f& c = mesh.vertices[static_cast<size_t>(t[2])];
    inward += (b - a).cross(c - a).dot((a + b + c) / 3.0f - kCentre) <= 0.0f;
  }
  EXPECT_EQ(inward, 0u);
  // The polyhedron's flat facets cut slightly inside the sphere: measured -0.26%.
  const double volume = 4.0 / 3.0 * std::numbers::pi * std::pow(kRadius, 3);
  EXPECT_NEAR(test::signedVolume(mesh), volume, 0.004 * volume);

  // The unconnected mesh has the same triangles, with border vertices duplicated.
  const Mesh loose = mesher.extractMesh(/*connected=*/false);
  EXPECT_EQ(loose.numTriangles(), mesh.numTriangles());
  EXPECT_GT(loose.numVertices(), mesh.numVertices());
  EXPECT_GT(test::topology(loose).boundary_edges, 0u);
}

TEST_P(MeshIntegratorBlockSize, TiltedPlaneIsExact) {
  const Eigen::Vector3f normal = Eigen::Vector3f(0.2f, -0.3f, 1.0f).normalized();
  const Eigen::Vector3f point(0.0031f, 0.0123f, 0.0457f);
  const auto sdf = [&](const Eigen::Vector3f& p) { return normal.dot(p - point); };
  TsdfLayer layer(LayerConfig{kVoxel, GetParam()});
  test::fillLayer(&layer, Eigen::Vector3f(-0.3f, -0.3f, -0.2f), Eigen::Vector3f(0.3f, 0.3f, 0.3f),
                  kTruncation, sdf);
  MeshIntegrator mesher(layer, MeshConfig{});
  mesher.update();
  const Mesh mesh = mesher.extractMesh(true);
  ASSERT_GT(mesh.numTriangles(), 1000u);
  float max_error = 0.0f;
  double max_angle = 0.0;
  for (size_t i = 0; i < mesh.numVertices(); ++i) {
    max_error = std::max(max_error, std::abs(sdf(mesh.vertices[i])));
    max_angle = std::max(max_angle, angleDegrees(mesh.normals[i], normal));
  }
  std::printf("plane vps %d: max vertex error %.3g m (%.3g voxel), max normal error %.4f deg\n",
              GetParam(), max_error, max_error / kVoxel, max_angle);
  // Linear interpolation is exact for a linear SDF: only float rounding remains.
  EXPECT_LE(max_error, 1e-6f);
  EXPECT_LE(max_angle, 0.05f);
  const test::Topology topo = test::topology(mesh);
  EXPECT_EQ(topo.non_manifold_edges, 0u);
  EXPECT_EQ(topo.misoriented_edges, 0u);
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3f& a = mesh.vertices[static_cast<size_t>(t[0])];
    const Eigen::Vector3f n = (mesh.vertices[static_cast<size_t>(t[1])] - a)
                                  .cross(mesh.vertices[static_cast<size_t>(t[2])] - a);
    ASSERT_GT(n.dot(normal), 0.0f);
  }
}

// Block borders add nothing and lose nothing: the same surface meshed with 8^3 and 16^3
// blocks has bit-identical vertices and the same triangles (up to vertex order).
TEST(MeshIntegrator, BlockSizeDoesNotChangeTheSurface) {
  const auto small = sphereLayer(8);
  const auto large = sphereLayer(16);
  MeshIntegrator m8(*small, MeshConfig{});
  MeshIntegrator m16(*large, MeshConfig{});
  m8.update();
  m16.update();
  const Mesh a = m8.extractMesh(true);
  const Mesh b = m16.extractMesh(true);
  ASSERT_EQ(a.numVertices(), b.numVertices());
  ASSERT_EQ(a.numTriangles(), b.numTriangles());
  const auto key = [](const Eigen::Vector3f& v) {
    return std::array<float, 3>{v.x(), v.y(), v.z()};
  };
  const auto triangleSet = [&](const Mesh& m) {
    std::set<std::array<std::array<float, 3>, 3>> set;
    for (const Eigen::Vector3i& t : m.triangles) {
      // Rotate so the smallest vertex comes first (keeps orientation).
      std::array<std::array<float, 3>, 3> tri = {key(m.vertices[static_cast<size_t>(t[0])]),
                                                 key(m.vertices[static_cast<size_t>(t[1])]),
                                                 key(m.vertices[static_cast<size_t>(t[2])])};
      std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
      set.insert(tri);
    }
    return set;
  };
  EXPECT_TRUE(triangleSet(a) == triangleSet(b));
}

INSTANTIATE_TEST_SUITE_P(VoxelsPerSide, MeshIntegratorBlockSize, ::testing::Values(8, 16));

TEST(MeshIntegrator, IncrementalUpdateRemeshesBlockAndLowerNeighbours) {
  const auto layer = sphereLayer(8);
  MeshIntegrator mesher(*layer, MeshConfig{});
  EXPECT_EQ(mesher.update(), layer->numBlocks());
  for (const auto& [key, block] : layer->blocks()) EXPECT_FALSE(block->updated());
  EXPECT_EQ(mesher.update(), 0u);  // nothing changed

  // A block on the surface: shrink the sphere slightly inside it only.
  const BlockIndex target = layer->blockIndexFromPoint(kCentre + Eigen::Vector3f(kRadius, 0, 0));
  Block* block = layer->getBlock(target);
  ASSERT_NE(block, nullptr);
  for (int i = 0; i < block->numVoxels(); ++i) {
    TsdfVoxel& v = block->voxel(i);
    if (v.weight > 0.0f) v.distance += 0.3f * kVoxel;
  }
  block->setUpdated(true);
  size_t expected = 1;
  for (int dz = -1; dz <= 0; ++dz) {
    for (int dy = -1; dy <= 0; ++dy) {
      for (int dx = -1; dx <= 0; ++dx) {
        if ((dx || dy || dz) && layer->getBlock(target + BlockIndex(dx, dy, dz))) ++expected;
      }
    }
  }
  EXPECT_EQ(expected, 8u);
  EXPECT_EQ(mesher.update(), expected);
  EXPECT_FALSE(block->updated());

  MeshIntegrator fresh(*layer, MeshConfig{});
  fresh.update(/*only_updated_blocks=*/false);
  expectIdentical(mesher.extractMesh(true), fresh.extractMesh(true));
  expectIdentical(mesher.extractMesh(false), fresh.extractMesh(false));
  // The re-mesh still closes up with the untouched neighbours.
  const test::Topology topo = test::topology(mesher.extractMesh(true));
  EXPECT_EQ(topo.boundary_edges, 0u);
  EXPECT_EQ(topo.misoriented_edges, 0u);
}

TEST(MeshIntegrator, KeepsFlagsWhenAskedAndMeshesAllBlocksOnRequest) {
  const auto layer = sphereLayer(8);
  MeshIntegrator mesher(*layer, MeshConfig{});
  EXPECT_EQ(mesher.update(true, /*clear_updated_flags=*/false), layer->numBlocks());
  for (const auto& [key, block] : layer->blocks()) EXPECT_TRUE(block->updated());
  EXPECT_EQ(mesher.update(false, true), layer->numBlocks());
  EXPECT_EQ(mesher.update(true, true), 0u);
  EXPECT_EQ(mesher.update(false, true), layer->numBlocks());
}

TEST(MeshIntegrator, RemovedBlockDropsItsMeshAndRemeshesLowerNeighbours) {
  const auto layer = sphereLayer(8);
  MeshIntegrator mesher(*layer, MeshConfig{});
  mesher.update();
  const BlockIndex target = layer->blockIndexFromPoint(kCentre + Eigen::Vector3f(0, kRadius, 0));
  ASSERT_TRUE(mesher.blockMeshes().contains(packGridIndex(target)));
  ASSERT_TRUE(layer->removeBlock(target));
  EXPECT_EQ(mesher.update(), 7u);
  EXPECT_FALSE(mesher.blockMeshes().contains(packGridIndex(target)));
  MeshIntegrator fresh(*layer, MeshConfig{});
  fresh.update(false);
  expectIdentical(mesher.extractMesh(true), fresh.extractMesh(true));
  // Now the surface has a hole.
  EXPECT_GT(test::topology(mesher.extractMesh(true)).boundary_edges, 0u);
}

TEST(MeshIntegrator, ThreadCountDoesNotChangeTheResult) {
  const auto layer = sphereLayer(8);
  MeshConfig one;
  one.num_threads = 1;
  MeshIntegrator m1(*layer, one);
  m1.update(false, false);
  for (const int threads : {2, 3, 7}) {
    MeshConfig config;
    config.num_threads = threads;
    MeshIntegrator mn(*layer, config);
    EXPECT_EQ(mn.update(false, false), layer->numBlocks());
    ASSERT_EQ(mn.blockMeshes().size(), m1.blockMeshes().size());
    for (const auto& [key, mesh] : m1.blockMeshes())
      expectIdentical(mesh, mn.blockMeshes().at(key));
    expectIdentical(m1.extractMesh(true), mn.extractMesh(true));
  }
}

TEST(MeshIntegrator, ColoursAreInterpolatedAndOptional) {
  TsdfLayer layer(LayerConfig{kVoxel, 8});
  const Eigen::Vector3f margin = Eigen::Vector3f::Constant(kRadius + 0.1f);
  test::fillLayer(&layer, kCentre - margin, kCentre + margin, kTruncation, sphereSdf, 1.0f,
                  [](const Eigen::Vector3f&) {
                    return Color{10, 200, 30};
                  });
  MeshIntegrator mesher(layer, MeshConfig{});
  mesher.update();
  const Mesh mesh = mesher.extractMesh(true);
  ASSERT_FALSE(mesh.colors.empty());
  for (const Color& c : mesh.colors) ASSERT_EQ(c, (Color{10, 200, 30}));

  MeshConfig plain;
  plain.use_color = false;
  plain.compute_normals = false;
  MeshIntegrator bare(layer, plain);
  bare.update(false);
  const Mesh m2 = bare.extractMesh(true);
  EXPECT_TRUE(m2.colors.empty());
  EXPECT_TRUE(m2.normals.empty());
  EXPECT_TRUE(m2.vertices == mesh.vertices);
  EXPECT_TRUE(m2.triangles == mesh.triangles);
}

TEST(MeshIntegrator, SkipsCubesWithLowWeightCorners) {
  TsdfLayer layer(LayerConfig{kVoxel, 8});
  const Eigen::Vector3f margin = Eigen::Vector3f::Constant(kRadius + 0.1f);
  test::fillLayer(&layer, kCentre - margin, kCentre + margin, kTruncation, sphereSdf, 0.5f);
  MeshConfig config;
  config.min_weight = 1.0f;
  MeshIntegrator strict(layer, config);
  strict.update(false);
  EXPECT_TRUE(strict.extractMesh(true).empty());
  config.min_weight = 0.5f;
  MeshIntegrator lenient(layer, config);
  lenient.update(false);
  EXPECT_FALSE(lenient.extractMesh(true).empty());
}

TEST(MeshIntegrator, MissingNeighbourBlockLeavesOpenBorderNoCrash) {
  // A single block: cubes at its +x/+y/+z faces need the (missing) neighbours and are skipped.
  TsdfLayer layer(LayerConfig{kVoxel, 8});
  const auto sdf = [](const Eigen::Vector3f& p) { return p.z() - 0.077f; };
  test::fillLayer(&layer, Eigen::Vector3f::Zero(), Eigen::Vector3f::Constant(0.15f), kTruncation,
                  sdf);
  ASSERT_EQ(layer.numBlocks(), 1u);
  MeshIntegrator mesher(layer, MeshConfig{});
  EXPECT_EQ(mesher.update(), 1u);
  const Mesh mesh = mesher.extractMesh(true);
  EXPECT_EQ(mesh.numTriangles(), 2u * 7u * 7u);  // 7 x 7 complete cubes cross z = 0.077
}

// Random fields exercise all 256 configurations, including the ambiguous ones: the
// connected mesh of a field that is positive on the region's border must be closed and
// consistently oriented (no cracks between cubes or blocks).
TEST(MeshIntegrator, RandomFieldGivesClosedOrientedSurface) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  for (int trial = 0; trial < 4; ++trial) {
    TsdfLayer layer(LayerConfig{1.0f, 8});
    for (int z = 0; z < 3; ++z) {
      for (int y = 0; y < 3; ++y) {
        for (int x = 0; x < 3; ++x) layer.allocateBlock(BlockIndex(x, y, z));
      }
    }
    std::set<int> configs;
    for (const auto& [key, block] : layer.blocks()) {
      for (int i = 0; i < block->numVoxels(); ++i) {
        const GlobalVoxelIndex g = block->index() * 8 + block->localIndex(i);
        const bool interior = g.minCoeff() >= 2 && g.maxCoeff() <= 21;
        float d = uniform(rng);
        if (std::abs(d) < 1e-3f) d = 0.5f;
        block->voxel(i).distance = interior ? d : 1.0f;
        block->voxel(i).weight = 1.0f;
      }
      block->setUpdated(true);
    }
    MeshIntegrator mesher(layer, MeshConfig{});
    mesher.update();
    const Mesh mesh = mesher.extractMesh(true);
    ASSERT_GT(mesh.numTriangles(), 10000u);
    const test::Topology topo = test::topology(mesh);
    EXPECT_EQ(topo.boundary_edges, 0u) << "trial " << trial;
    EXPECT_EQ(topo.non_manifold_edges, 0u) << "trial " << trial;
    EXPECT_EQ(topo.misoriented_edges, 0u) << "trial " << trial;
    EXPECT_GT(test::signedVolume(mesh), 0.0) << "trial " << trial;
  }
}

TEST(MeshConfig, Validate) {
  EXPECT_EQ(MeshConfig{}.validate(), "");
  MeshConfig c;
  c.min_weight = 0.0f;
  EXPECT_NE(c.validate().find("min_weight"), std::string::npos);
  c = MeshConfig{};
  c.min_weight = std::nanf("");
  EXPECT_NE(c.validate().find("min_weight"), std::string::npos);
  c = MeshConfig{};
  c.num_threads = 0;
  EXPECT_NE(c.validate().find("num_threads"), std::string::npos);
  TsdfLayer layer(LayerConfig{});
  EXPECT_THROW(MeshIntegrator(layer, c), std::invalid_argument);
}

}  // namespace
}  // namespace cblox
