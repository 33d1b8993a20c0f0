#include "core/geometry/point_cloud.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

namespace cblox {
namespace {

TEST(PointCloud, Basics) {
  PointCloud cloud;
  EXPECT_EQ(cloud.size(), 0u);
  EXPECT_FALSE(cloud.hasColors());
  cloud.reserve(10);
  EXPECT_GE(cloud.points.capacity(), 10u);
  cloud.points.emplace_back(1.0f, 2.0f, 3.0f);
  EXPECT_EQ(cloud.size(), 1u);
  EXPECT_FALSE(cloud.hasColors());
  EXPECT_TRUE(cloud.isConsistent());
  cloud.colors.push_back(Color{1, 2, 3});
  EXPECT_TRUE(cloud.hasColors());
  EXPECT_TRUE(cloud.isConsistent());
  cloud.colors.push_back(Color{1, 2, 3});
  EXPECT_FALSE(cloud.isConsistent());
  cloud.clear();
  EXPECT_EQ(cloud.size(), 0u);
  EXPECT_FALSE(cloud.hasColors());
}

TEST(PointCloud, TransformPointCloud) {
  PointCloud cloud_B;
  cloud_B.points = {{1.0f, 0.0f, 0.0f}, {0.0f, 2.0f, 0.5f}};
  cloud_B.colors = {Color{1, 2, 3}, Color{4, 5, 6}};
  // T_A_B: 90 degrees about z, then translate by (1, 2, 3).
  const Transformation T_A_B(Eigen::Quaternionf(Eigen::AngleAxisf(std::numbers::pi_v<float> / 2,
                                                                  Eigen::Vector3f::UnitZ())),
                             Eigen::Vector3f(1.0f, 2.0f, 3.0f));
  const PointCloud cloud_A = transformPointCloud(T_A_B, cloud_B);
  ASSERT_EQ(cloud_A.size(), 2u);
  EXPECT_LE((cloud_A.points[0] - Eigen::Vector3f(1.0f, 3.0f, 3.0f)).norm(), 1e-6f);
  EXPECT_LE((cloud_A.points[1] - Eigen::Vector3f(-1.0f, 2.0f, 3.5f)).norm(), 1e-6f);
  EXPECT_EQ(cloud_A.colors, cloud_B.colors);
  // Matches point-wise SE3 application, and the inverse maps back.
  for (size_t i = 0; i < cloud_B.size(); ++i) {
    EXPECT_LE((cloud_A.points[i] - T_A_B * cloud_B.points[i]).norm(), 1e-6f);
  }
  const PointCloud back = transformPointCloud(T_A_B.inverse(), cloud_A);
  for (size_t i = 0; i < cloud_B.size(); ++i) {
    EXPECT_LE((back.points[i] - cloud_B.points[i]).norm(), 1e-6f);
  }
  EXPECT_EQ(transformPointCloud(T_A_B, PointCloud{}).size(), 0u);
}

}  // namespace
}  // namespace cblox
