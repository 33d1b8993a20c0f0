#include "drivers/synthetic/analytic_scene.h"

#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "drivers/synthetic/scenes.h"

namespace cblox {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

PinholeIntrinsics vgaIntrinsics() {
  PinholeIntrinsics in;
  in.fx = 585.0;
  in.fy = 585.0;
  in.cx = 320.0;
  in.cy = 240.0;
  in.width = 640;
  in.height = 480;
  return in;
}

// Normalised ray direction through pixel (u, v) in the camera frame.
Vector3d pixelRay(const PinholeIntrinsics& in, int u, int v) {
  return Vector3d((u - in.cx) / in.fx, (v - in.cy) / in.fy, 1.0);
}

TEST(AnalyticSceneTest, FrontoParallelPlaneRendersExactDepth) {
  const AnalyticScene scene = makePlaneScene(Vector3d(0, 0, 2), Vector3d(0, 0, -1));
  const PinholeCamera camera(vgaIntrinsics());
  DepthImage depth;
  ColorImage color;
  scene.renderDepth(Transformationd(), camera, &depth, &color, 100.0);
  ASSERT_EQ(depth.width, 640);
  ASSERT_EQ(depth.height, 480);
  ASSERT_EQ(color.width, 640);
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      ASSERT_EQ(depth(u, v), 2.0f) << "pixel " << u << ", " << v;
    }
  }
}

TEST(AnalyticSceneTest, PosedCameraSeesTheSamePlaneDepth) {
  // The camera at an arbitrary pose T_G_C looks at the plane z_C = 2 expressed in G.
  const Transformationd T_G_C = Transformationd::exp(
      (Eigen::Matrix<double, 6, 1>() << 1.0, -2.0, 0.5, 0.3, -0.7, 1.1).finished());
  const Vector3d point_G = T_G_C * Vector3d(0, 0, 2);
  const Vector3d normal_G = T_G_C.rotationMatrix() * Vector3d(0, 0, -1);
  const AnalyticScene scene = makePlaneScene(point_G, normal_G);
  DepthImage depth;
  scene.renderDepth(T_G_C, PinholeCamera(vgaIntrinsics()), &depth, nullptr, 100.0);
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      ASSERT_NEAR(depth(u, v), 2.0f, 2e-6) << "pixel " << u << ", " << v;
    }
  }
}

TEST(AnalyticSceneTest, PlaneTiltedAboutYGivesAnalyticDepth) {
  // Plane through (0, 0, 2) with normal (sin a, 0, cos a): a fronto-parallel plane rotated
  // by a about the camera y axis. Along the ray z * (x, y, 1): z = 2 cos a / (x sin a + cos a).
  const double a = 30.0 * std::numbers::pi / 180.0;
  const Vector3d normal(std::sin(a), 0.0, std::cos(a));
  const AnalyticScene scene = makePlaneScene(Vector3d(0, 0, 2), -normal);
  const PinholeIntrinsics in = vgaIntrinsics();
  DepthImage depth;
  scene.renderDepth(Transformationd(), PinholeCamera(in), &depth, nullptr, 100.0);
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      const double x = (u - in.cx) / in.fx;
      const double expected = 2.0 * std::cos(a) / (x * std::sin(a) + std::cos(a));
      ASSERT_NEAR(depth(u, v), expected, 1e-6 * expected) << "pixel " << u << ", " << v;
    }
  }
  // Depth varies along a row but not along a column.
  EXPECT_GT(depth(0, 240), depth(639, 240));
  EXPECT_FLOAT_EQ(depth(100, 0), depth(100, 479));
}

TEST(AnalyticSceneTest, SphereDepthAndSilhouette) {
  const double distance = 3.0, radius = 0.5;
  AnalyticScene scene;
  scene.add(Sphere{Vector3d(0, 0, distance), radius, CheckerTexture::solid({255, 0, 0})});
  const PinholeIntrinsics in = vgaIntrinsics();
  DepthImage depth;
  ColorImage color;
  scene.renderDepth(Transformationd(), PinholeCamera(in), &depth, &color, 100.0);

  // Centre pixel (cx, cy) = (320, 240) looks straight at the sphere centre.
  EXPECT_FLOAT_EQ(depth(320, 240), static_cast<float>(distance - radius));
  EXPECT_EQ(color(320, 240), (Color{255, 0, 0}));

  // A ray hits iff its angle to the axis is below asin(r / D): on the image plane (z = 1)
  // that is a disc of radius tan(asin(r / D)) = r / sqrt(D^2 - r^2).
  const double tan_radius = radius / std::sqrt(distance * distance - radius * radius);
  const Vector3d c(0, 0, distance);
  int hits_on_centre_row = 0;
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      const Vector3d ray = pixelRay(in, u, v);
      const double rho = ray.head<2>().norm();
      if (std::abs(rho - tan_radius) < 1e-9) continue;  // on the silhouette: either is fine
      if (rho > tan_radius) {
        ASSERT_EQ(depth(u, v), 0.0f) << "pixel " << u << ", " << v;
        ASSERT_EQ(color(u, v), Color{});
        continue;
      }
      // Analytic nearest root of |t d - c| = r for the unit direction d.
      const Vector3d d = ray.normalized();
      const double b = d.dot(c);
      const double t = b - std::sqrt(b * b - (c.squaredNorm() - radius * radius));
      ASSERT_NEAR(depth(u, v), t * d.z(), 1e-6) << "pixel " << u << ", " << v;
      if (v == 240) ++hits_on_centre_row;
    }
  }
  // Silhouette radius in pixels along the centre row: fx * tan_radius (~98.9 px).
  const int expected_half_width = static_cast<int>(std::floor(in.fx * tan_radius));
  EXPECT_EQ(hits_on_centre_row, 2 * expected_half_width + 1);
}

TEST(AnalyticSceneTest, MaxRangeCutsOffFarSurfaces) {
  const AnalyticScene scene = makePlaneScene(Vector3d(0, 0, 2), Vector3d(0, 0, -1));
  const PinholeIntrinsics in = vgaIntrinsics();
  DepthImage depth;
  // Range along the ray is 2 * |ray|, so only pixels with |ray| <= 1.1 see the plane.
  scene.renderDepth(Transformationd(), PinholeCamera(in), &depth, nullptr, 2.2);
  for (int v = 0; v < depth.height; v += 7) {
    for (int u = 0; u < depth.width; u += 7) {
      const double range = 2.0 * pixelRay(in, u, v).norm();
      if (std::abs(range - 2.2) < 1e-9) continue;
      EXPECT_EQ(depth(u, v), range <= 2.2 ? 2.0f : 0.0f) << "pixel " << u << ", " << v;
    }
  }
}

TEST(AnalyticSceneTest, RaycastHitsLieOnTheZeroLevelSet) {
  const AnalyticScene scene = makeDemoRoom();
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> ux(-2.9, 2.9), uy(-1.9, 1.9), uz(0.1, 2.9);
  std::normal_distribution<double> gauss(0.0, 1.0);
  int rays = 0;
  while (rays < 20000) {
    const Vector3d origin(ux(rng), uy(rng), uz(rng));
    if (scene.signedDistance(origin) < 0.01) continue;  // start in free space
    const Vector3d dir = Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
    double range = 0.0;
    Color color;
    ASSERT_TRUE(scene.raycast(origin, dir, 100.0, &range, &color))
        << "the room is closed: every ray must hit";
    ASSERT_GT(range, 0.0);
    const Vector3d hit = origin + range * dir;
    ASSERT_LT(std::abs(scene.signedDistance(hit)), 1e-9) << "hit " << hit.transpose();
    // The hit is the nearest surface: the segment before it stays in free space.
    ASSERT_GE(scene.signedDistance(origin + 0.5 * range * dir), 0.0);
    ++rays;
  }
}

TEST(AnalyticSceneTest, SignedDistanceKnownValues) {
  const AnalyticScene sphere_scene = makeSphereScene();
  EXPECT_NEAR(sphere_scene.signedDistance(Vector3d(0, 0, 0)), -0.5, 1e-12);
  EXPECT_NEAR(sphere_scene.signedDistance(Vector3d(0, 0, 2)), 1.5, 1e-12);      // sphere nearer
  EXPECT_NEAR(sphere_scene.signedDistance(Vector3d(2, 0, 0)), 0.5, 1e-12);      // ground nearer
  EXPECT_NEAR(sphere_scene.signedDistance(Vector3d(5, 5, 0.5)), 1.0, 1e-12);    // above ground
  EXPECT_NEAR(sphere_scene.signedDistance(Vector3d(5, 5, -0.7)), -0.2, 1e-12);  // below

  AnalyticScene room;
  room.add(Room{Vector3d(-3, -2, 0), Vector3d(3, 2, 3), {}});
  EXPECT_NEAR(room.signedDistance(Vector3d(0, 0, 1)), 1.0, 1e-12);  // inside: positive
  EXPECT_NEAR(room.signedDistance(Vector3d(2.5, 0, 1.5)), 0.5, 1e-12);
  EXPECT_NEAR(room.signedDistance(Vector3d(4, 3, 1.5)), -std::sqrt(2.0), 1e-12);  // outside

  AnalyticScene furniture;
  furniture.add(SolidBox{Vector3d(0, 0, 0), Vector3d(1, 1, 1), {}});
  furniture.add(Cylinder{5, 0, 0.5, 0, 2, {}});
  EXPECT_NEAR(furniture.signedDistance(Vector3d(0.5, 0.5, 0.6)), -0.4, 1e-12);
  EXPECT_NEAR(furniture.signedDistance(Vector3d(2, 2, 0.5)), std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(furniture.signedDistance(Vector3d(5, 0, 1)), -0.5, 1e-12);   // axis
  EXPECT_NEAR(furniture.signedDistance(Vector3d(5, 1.5, 1)), 1.0, 1e-12);  // side
  EXPECT_NEAR(furniture.signedDistance(Vector3d(5, 0, 3)), 1.0, 1e-12);    // above cap
  EXPECT_NEAR(furniture.signedDistance(Vector3d(5, 3.5, 6)), 5.0, 1e-12);  // cap rim

  EXPECT_TRUE(std::isinf(AnalyticScene().signedDistance(Vector3d::Zero())));
}

TEST(AnalyticSceneTest, EveryRayFromInsideABoxHits) {
  AnalyticScene scene;
  scene.add(Room{Vector3d(-3, -2, 0), Vector3d(3, 2, 3), {}});
  const Vector3d origin(0.5, -0.25, 1.0);
  // Axis-aligned rays (zero direction components) hit the walls at the analytic distance.
  const std::pair<Vector3d, double> axis_rays[] = {
      {Vector3d::UnitX(), 2.5},   {-Vector3d::UnitX(), 3.5}, {Vector3d::UnitY(), 2.25},
      {-Vector3d::UnitY(), 1.75}, {Vector3d::UnitZ(), 2.0},  {-Vector3d::UnitZ(), 1.0}};
  for (const auto& [dir, expected] : axis_rays) {
    double range = 0.0;
    ASSERT_TRUE(scene.raycast(origin, dir, 100.0, &range)) << dir.transpose();
    EXPECT_DOUBLE_EQ(range, expected) << dir.transpose();
  }
  // Random origins and directions, and a full-sphere camera: every ray hits.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(-2.99, 2.99), uy(-1.99, 1.99), uz(0.01, 2.99);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int i = 0; i < 10000; ++i) {
    const Vector3d o(ux(rng), uy(rng), uz(rng));
    const Vector3d d = Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
    double range = 0.0;
    ASSERT_TRUE(scene.raycast(o, d, 100.0, &range)) << o.transpose() << " / " << d.transpose();
    EXPECT_LT(std::abs(scene.signedDistance(o + range * d)), 1e-9);
  }
  for (const Transformationd& T_G_C :
       makeOrbitTrajectory(Vector3d(0, 0, 1.5), 1.5, 0.0, 6, Vector3d(0, 0, 1.0))) {
    DepthImage depth;
    scene.renderDepth(T_G_C, PinholeCamera(vgaIntrinsics()), &depth, nullptr, 100.0);
    for (const float d : depth.data) ASSERT_GT(d, 0.0f);
  }
}

TEST(AnalyticSceneTest, RaycastMissesAndRespectsMaxRange) {
  const AnalyticScene scene = makeSphereScene();
  double range = -1.0;
  Color color{1, 2, 3};
  // Upwards from above the ground: nothing there.
  EXPECT_FALSE(scene.raycast(Vector3d(3, 0, 1), Vector3d::UnitZ(), 100.0, &range, &color));
  EXPECT_EQ(range, -1.0);
  EXPECT_EQ(color, (Color{1, 2, 3}));
  // Towards the sphere: hit at 2.5, but not within 2.4.
  EXPECT_FALSE(scene.raycast(Vector3d(3, 0, 0), -Vector3d::UnitX(), 2.4, &range));
  ASSERT_TRUE(scene.raycast(Vector3d(3, 0, 0), -Vector3d::UnitX(), 2.6, &range));
  EXPECT_DOUBLE_EQ(range, 2.5);
  // From inside the sphere the inner surface is hit.
  ASSERT_TRUE(scene.raycast(Vector3d(0, 0, 0), Vector3d::UnitX(), 10.0, &range));
  EXPECT_DOUBLE_EQ(range, 0.5);
  // A non-unit direction is normalised: range stays Euclidean.
  ASSERT_TRUE(scene.raycast(Vector3d(3, 0, 0), Vector3d(-4, 0, 0), 10.0, &range));
  EXPECT_DOUBLE_EQ(range, 2.5);
}

TEST(AnalyticSceneTest, CheckerColourAlternatesOnThePlane) {
  const Color a{40, 40, 160}, b{220, 220, 220};
  AnalyticScene scene;
  scene.add(Plane{Vector3d::Zero(), Vector3d::UnitZ(), CheckerTexture{a, b, 1.0}});
  auto colorAt = [&](double x, double y) {
    double range = 0.0;
    Color c;
    EXPECT_TRUE(scene.raycast(Vector3d(x, y, 1.0), -Vector3d::UnitZ(), 10.0, &range, &c));
    return c;
  };
  const Color c00 = colorAt(0.5, 0.5);
  EXPECT_TRUE(c00 == a || c00 == b);
  EXPECT_NE(colorAt(1.5, 0.5), c00);
  EXPECT_NE(colorAt(0.5, 1.5), c00);
  EXPECT_EQ(colorAt(1.5, 1.5), c00);
  EXPECT_EQ(colorAt(0.6, 0.4), c00);
}

TEST(AnalyticSceneTest, RenderedColourMatchesRaycast) {
  const AnalyticScene scene = makeDemoRoom();
  const Transformationd T_G_C = lookAt(Vector3d(-2.0, -1.5, 1.6), Vector3d(1.0, 0.5, 0.75));
  const PinholeIntrinsics in = vgaIntrinsics();
  DepthImage depth;
  ColorImage color;
  scene.renderDepth(T_G_C, PinholeCamera(in), &depth, &color, 20.0);
  int distinct_colors = 0;
  Color previous;
  for (int v = 0; v < in.height; v += 13) {
    for (int u = 0; u < in.width; u += 11) {
      const Vector3d d_C = pixelRay(in, u, v).normalized();
      double range = 0.0;
      Color c;
      ASSERT_TRUE(
          scene.raycast(T_G_C.translation(), T_G_C.rotationMatrix() * d_C, 20.0, &range, &c));
      EXPECT_FLOAT_EQ(depth(u, v), static_cast<float>(range * d_C.z()));
      EXPECT_EQ(color(u, v), c);
      if (!(c == previous)) ++distinct_colors;
      previous = c;
    }
  }
  EXPECT_GT(distinct_colors, 10);  // textured, not flat
}

TEST(AnalyticSceneTest, RejectsMalformedPrimitives) {
  AnalyticScene scene;
  EXPECT_THROW(scene.add(Sphere{Vector3d::Zero(), 0.0, {}}), std::invalid_argument);
  EXPECT_THROW(scene.add(Plane{Vector3d::Zero(), Vector3d::Zero(), {}}), std::invalid_argument);
  EXPECT_THROW(scene.add(SolidBox{Vector3d(1, 0, 0), Vector3d(0, 1, 1), {}}),
               std::invalid_argument);
  EXPECT_THROW(scene.add(Cylinder{0, 0, 1, 2, 1, {}}), std::invalid_argument);
  EXPECT_TRUE(scene.primitives().empty());
  scene.add(Plane{Vector3d::Zero(), Vector3d(0, 0, 5), {}});  // normal gets normalised
  EXPECT_DOUBLE_EQ(std::get<Plane>(scene.primitives()[0]).normal.norm(), 1.0);
  DepthImage depth;
  EXPECT_THROW(
      scene.renderDepth(Transformationd(), PinholeCamera(vgaIntrinsics()), &depth, nullptr, 0.0),
      std::invalid_argument);
}

}  // namespace
}  // namespace cblox
