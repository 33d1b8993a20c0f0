#include "drivers/synthetic/scenes.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

namespace cblox {
namespace {

using Eigen::Vector3d;

TEST(ScenesTest, OrbitTrajectoryLooksAtTargetWithYDown) {
  const Vector3d centre(0.5, -0.5, 1.0), look_at(0.2, 0.1, 0.8);
  const double radius = 2.0, height = 0.4;
  const int n = 12;
  const std::vector<Transformationd> poses =
      makeOrbitTrajectory(centre, radius, height, n, look_at);
  ASSERT_EQ(poses.size(), static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) {
    const Transformationd& T_G_C = poses[static_cast<size_t>(k)];
    const Vector3d p = T_G_C.translation();
    const double angle = 2.0 * std::numbers::pi * k / n;
    EXPECT_NEAR(
        (p - (centre + Vector3d(radius * std::cos(angle), radius * std::sin(angle), height)))
            .norm(),
        0.0, 1e-12);
    const Eigen::Matrix3d R = T_G_C.rotationMatrix();
    EXPECT_NEAR((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
    // z axis at the target: the target projects onto the optical axis.
    const Vector3d target_C = T_G_C.inverse() * look_at;
    EXPECT_GT(target_C.z(), 0.0);
    EXPECT_NEAR(target_C.x(), 0.0, 1e-9);
    EXPECT_NEAR(target_C.y(), 0.0, 1e-9);
    // x horizontal, y pointing down.
    EXPECT_NEAR(R.col(0).z(), 0.0, 1e-12);
    EXPECT_LT(R.col(1).z(), 0.0);
  }
  EXPECT_TRUE(makeOrbitTrajectory(centre, radius, height, 0, look_at).empty());
  EXPECT_THROW(makeOrbitTrajectory(Vector3d::Zero(), 0.0, 0.0, 3, Vector3d::Zero()),
               std::invalid_argument);
  EXPECT_THROW(lookAt(Vector3d::Zero(), Vector3d(0, 0, -1)), std::invalid_argument);
}

TEST(ScenesTest, DemoRoomIsClosedAndFurnished) {
  const AnalyticScene room = makeDemoRoom();
  EXPECT_GE(room.primitives().size(), 4u);
  // Free space in the middle, matter behind walls and inside furniture.
  EXPECT_GT(room.signedDistance(Vector3d(0, 0, 1.5)), 0.5);
  EXPECT_LT(room.signedDistance(Vector3d(0, 0, 3.5)), 0.0);                    // above the ceiling
  EXPECT_NEAR(room.signedDistance(Vector3d(1.0, 0.5, 0.745)), -0.025, 1e-12);  // table top
  EXPECT_NEAR(room.signedDistance(Vector3d(-1.0, -0.8, 0.3)), -0.3, 1e-12);    // sphere
  EXPECT_NEAR(room.signedDistance(Vector3d(-1.8, 1.2, 1.5)), -0.2, 1e-12);     // pillar
  EXPECT_NEAR(room.signedDistance(Vector3d(1.0, 0.5, 1.77)), 1.0, 1e-12);      // above table

  // An orbiting camera inside the room sees a surface in every pixel, within the room size.
  PinholeIntrinsics in;
  in.fx = in.fy = 300.0;
  in.cx = 159.5;
  in.cy = 119.5;
  in.width = 320;
  in.height = 240;
  const PinholeCamera camera(in);
  for (const Transformationd& T_G_C :
       makeOrbitTrajectory(Vector3d(0, 0, 1.5), 1.8, 0.0, 8, Vector3d(0, 0, 0.8))) {
    ASSERT_GT(room.signedDistance(T_G_C.translation()), 0.0);
    DepthImage depth;
    room.renderDepth(T_G_C, camera, &depth, nullptr, 20.0);
    for (const float d : depth.data) {
      ASSERT_GT(d, 0.0f);
      ASSERT_LT(d, 7.9f);  // room diagonal sqrt(36 + 16 + 9) ~ 7.8 m
    }
  }
}

TEST(ScenesTest, SphereSceneLayout) {
  const AnalyticScene scene = makeSphereScene();
  double range = 0.0;
  ASSERT_TRUE(scene.raycast(Vector3d(0, 0, 3), -Vector3d::UnitZ(), 10.0, &range));
  EXPECT_DOUBLE_EQ(range, 2.5);  // top of the sphere
  ASSERT_TRUE(scene.raycast(Vector3d(2, 0, 3), -Vector3d::UnitZ(), 10.0, &range));
  EXPECT_DOUBLE_EQ(range, 3.5);  // ground at z = -0.5
}

TEST(ScenesTest, PlaneSceneNormalisesNormal) {
  const AnalyticScene scene = makePlaneScene(Vector3d(0, 0, 1), Vector3d(0, 0, 10));
  EXPECT_NEAR(scene.signedDistance(Vector3d(0, 0, 4)), 3.0, 1e-12);
  EXPECT_NEAR(scene.signedDistance(Vector3d(0, 0, 0)), -1.0, 1e-12);
  EXPECT_THROW(makePlaneScene(Vector3d::Zero(), Vector3d::Zero()), std::invalid_argument);
}

}  // namespace
}  // namespace cblox
