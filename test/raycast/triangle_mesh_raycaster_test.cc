#include "core/raycast/triangle_mesh_raycaster.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/geometry/closest_point_on_triangle.h"
#include "core/mesh/primitive_meshes.h"

namespace cblox {
namespace {

const Color kGrey{128, 128, 128};

std::unique_ptr<TriangleMeshRaycaster> makeRaycaster(const Mesh& mesh) {
  std::string error;
  auto raycaster = TriangleMeshRaycaster::create(mesh, &error);
  EXPECT_NE(raycaster, nullptr) << error;
  return raycaster;
}

Mesh unitBoxAt(const Eigen::Vector3f& min, const Eigen::Vector3f& max) {
  Mesh mesh;
  appendBox(&mesh, Eigen::AlignedBox3f(min, max), kGrey);
  return mesh;
}

TEST(TriangleMeshRaycasterTest, HitsAxisAlignedBoxAtExactDistanceWithOutwardNormal) {
  const auto raycaster = makeRaycaster(unitBoxAt({-1, -1, 3}, {1, 1, 5}));
  RaycastHit hit;
  ASSERT_TRUE(raycaster->intersect(Ray{{0.3f, -0.2f, 0}, {0, 0, 1}}, &hit));
  EXPECT_FLOAT_EQ(hit.t, 3.0f);  // within 4 ulps: Embree's kernel (per ISA) may round
  EXPECT_TRUE(hit.normal.isApprox(Eigen::Vector3f(0, 0, -1)));
  // Non-unit direction scaled to z = 1: t is the z depth.
  ASSERT_TRUE(raycaster->intersect(Ray{{0, 0, 0}, {0.25f, 0.1f, 1}}, &hit));
  EXPECT_FLOAT_EQ(hit.t, 3.0f);
  // Barycentrics reproduce the hit point.
  const Eigen::Vector3i& tri = raycaster->mesh().triangles[hit.triangle];
  const auto& v = raycaster->mesh().vertices;
  const Eigen::Vector3f p = (1 - hit.u - hit.v) * v[tri[0]] + hit.u * v[tri[1]] + hit.v * v[tri[2]];
  EXPECT_TRUE(p.isApprox(Eigen::Vector3f(0.75f, 0.3f, 3.0f), 1e-6f)) << p.transpose();
  // Misses: pointing away, beyond t_far, from inside the t_near gap.
  EXPECT_FALSE(raycaster->intersect(Ray{{0, 0, 0}, {0, 0, -1}}, &hit));
  EXPECT_FALSE(hit.hit());
  EXPECT_FALSE(raycaster->intersect(Ray{{0, 0, 0}, {0, 0, 1}, 0.0f, 2.9f}, &hit));
  ASSERT_TRUE(raycaster->intersect(Ray{{0, 0, 0}, {0, 0, 1}, 3.5f}, &hit));
  EXPECT_FLOAT_EQ(hit.t, 5.0f);  // the back face
  EXPECT_TRUE(raycaster->occluded(Ray{{0, 0, 0}, {0, 0, 1}}));
  EXPECT_FALSE(raycaster->occluded(Ray{{0, 0, 0}, {0, 0, 1}, 0.0f, 2.5f}));
}

TEST(TriangleMeshRaycasterTest, PacketsAgreeWithSingleRays) {
  Mesh mesh = unitBoxAt({-1, -1, 3}, {1, 1, 5});
  appendSphere(&mesh, Eigen::Vector3f(0.5f, 0.5f, 2.0f), 0.4f, 16, 32, kGrey);
  const auto raycaster = makeRaycaster(mesh);
  std::vector<Ray> rays;
  for (int v = 0; v < 23; ++v) {
    for (int u = 0; u < 37; ++u) {
      rays.push_back(Ray{{0, 0, 0}, {(u - 18) / 20.0f, (v - 11) / 20.0f, 1.0f}});
    }
  }
  std::vector<RaycastHit> hits(rays.size());
  raycaster->intersect(rays, hits);
  int hit_count = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    RaycastHit single;
    raycaster->intersect(rays[i], &single);
    // A ray through a shared edge may report either triangle; the distance is the same.
    ASSERT_EQ(single.hit(), hits[i].hit()) << i;
    EXPECT_EQ(single.t, hits[i].t) << i;
    hit_count += single.hit();
  }
  EXPECT_GT(hit_count, 100);
  EXPECT_LT(hit_count, static_cast<int>(rays.size()));
}

TEST(TriangleMeshRaycasterTest, PinholeRowsAgreeWithSingleRays) {
  Mesh mesh = unitBoxAt({-1, -1, 3}, {1, 1, 5});
  appendSphere(&mesh, Eigen::Vector3f(0.5f, 0.5f, 2.0f), 0.4f, 16, 32, kGrey);
  const auto raycaster = makeRaycaster(mesh);
  const PinholeIntrinsics K{40.0, 42.0, 18.5, 10.5, 37, 23};  // not multiples of 4
  const Eigen::Matrix3f R =
      Eigen::AngleAxisf(0.2f, Eigen::Vector3f(0.3f, 1.0f, 0.1f).normalized()).toRotationMatrix();
  const Eigen::Vector3f origin(0.1f, -0.2f, 0.05f);
  const int row_begin = 3, row_end = 21;
  std::vector<RaycastHit> hits(static_cast<size_t>((row_end - row_begin) * K.width));
  raycaster->intersectPinholeRows(R, origin, K, row_begin, row_end, hits);
  int hit_count = 0;
  for (int v = row_begin; v < row_end; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const Ray ray{origin, R * Eigen::Vector3f((u - 18.5f) / 40.0f, (v - 10.5f) / 42.0f, 1.0f)};
      RaycastHit single;
      raycaster->intersect(ray, &single);
      const RaycastHit& row_hit = hits[static_cast<size_t>(v - row_begin) * K.width + u];
      ASSERT_EQ(single.hit(), row_hit.hit()) << u << ", " << v;
      EXPECT_EQ(single.t, row_hit.t) << u << ", " << v;
      if (single.hit()) {
        EXPECT_TRUE(single.normal.isApprox(row_hit.normal, 1e-6f));
      }
      hit_count += single.hit();
    }
  }
  EXPECT_GT(hit_count, 100);
}

TEST(TriangleMeshRaycasterTest, ClosestPointIsExactOnFacesEdgesAndCorners) {
  const auto raycaster = makeRaycaster(unitBoxAt({0, 0, 0}, {1, 1, 1}));
  // Face region.
  ClosestSurfacePoint c = raycaster->closestPoint({0.3, 0.6, 1.25});
  ASSERT_TRUE(c.found());
  EXPECT_NEAR(c.distance, 0.25, 1e-12);
  EXPECT_TRUE(c.point.isApprox(Eigen::Vector3d(0.3, 0.6, 1.0), 1e-12));
  // Edge region: closest to the edge x = 1, z = 1.
  c = raycaster->closestPoint({1.3, 0.5, 1.4});
  EXPECT_NEAR(c.distance, 0.5, 1e-12);
  // Corner region.
  c = raycaster->closestPoint({-1, -2, -2});
  EXPECT_NEAR(c.distance, 3.0, 1e-12);
  EXPECT_TRUE(c.point.isApprox(Eigen::Vector3d(0, 0, 0), 1e-12));
  // Inside: distance to the nearest face.
  c = raycaster->closestPoint({0.5, 0.9, 0.5});
  EXPECT_NEAR(c.distance, 0.1, 1e-7);
  // Beyond max_distance: not found.
  EXPECT_FALSE(raycaster->closestPoint({0.5, 0.5, 3.0}, 1.5).found());
  EXPECT_TRUE(raycaster->closestPoint({0.5, 0.5, 3.0}, 2.0).found());
}

TEST(TriangleMeshRaycasterTest, ClosestPointMatchesBruteForceOnASphere) {
  Mesh mesh;
  appendSphere(&mesh, Eigen::Vector3f(0.2f, -0.1f, 0.3f), 1.0f, 12, 24, kGrey);
  const auto raycaster = makeRaycaster(mesh);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(-2.0, 2.0);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p(coord(rng), coord(rng), coord(rng));
    double best = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3i& t : mesh.triangles) {
      const Eigen::Vector3d q = closestPointOnTriangle(p, mesh.vertices[t[0]].cast<double>(),
                                                       mesh.vertices[t[1]].cast<double>(),
                                                       mesh.vertices[t[2]].cast<double>());
      best = std::min(best, (q - p).norm());
    }
    EXPECT_NEAR(raycaster->closestPoint(p).distance, best, 1e-12) << p.transpose();
  }
}

TEST(TriangleMeshRaycasterTest, RejectsEmptyInvalidAndNonFiniteMeshes) {
  std::string error;
  EXPECT_EQ(TriangleMeshRaycaster::create(Mesh{}, &error), nullptr);
  EXPECT_NE(error.find("no triangle"), std::string::npos) << error;

  Mesh bad_index = unitBoxAt({0, 0, 0}, {1, 1, 1});
  bad_index.triangles.push_back({0, 1, 99});
  EXPECT_EQ(TriangleMeshRaycaster::create(bad_index, &error), nullptr);
  EXPECT_NE(error.find("invalid mesh"), std::string::npos) << error;

  Mesh nan_vertex = unitBoxAt({0, 0, 0}, {1, 1, 1});
  nan_vertex.vertices[3].x() = std::nanf("");
  EXPECT_EQ(TriangleMeshRaycaster::create(nan_vertex, &error), nullptr);
  EXPECT_NE(error.find("vertex 3 is not finite"), std::string::npos) << error;

  // A degenerate triangle is accepted and never hit.
  Mesh degenerate = unitBoxAt({0, 0, 0}, {1, 1, 1});
  degenerate.vertices.push_back({0.5f, 0.5f, -1.0f});
  degenerate.colors.push_back(kGrey);
  degenerate.triangles.push_back({8, 8, 8});
  const auto raycaster = makeRaycaster(degenerate);
  RaycastHit hit;
  ASSERT_TRUE(raycaster->intersect(Ray{{0.5f, 0.5f, -2.0f}, {0, 0, 1}}, &hit));
  EXPECT_FLOAT_EQ(hit.t, 2.0f);
}

}  // namespace
}  // namespace cblox
