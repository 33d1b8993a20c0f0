#include "core/geometry/depth_to_point_cloud.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

namespace cblox {
namespace {

constexpr int kWidth = 8;
constexpr int kHeight = 6;

PinholeCamera smallCamera() {
  PinholeIntrinsics in;
  in.fx = 10.0;
  in.fy = 12.0;
  in.cx = 3.5;
  in.cy = 2.5;
  in.width = kWidth;
  in.height = kHeight;
  return PinholeCamera(in);
}

Color colorAt(int u, int v) {
  return Color{static_cast<uint8_t>(u), static_cast<uint8_t>(v), static_cast<uint8_t>(u + v)};
}

ColorImage gradientColors(int width, int height) {
  ColorImage image(width, height);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) image(u, v) = colorAt(u, v);
  }
  return image;
}

TEST(DepthToPointCloud, FrontoParallelPlane) {
  const PinholeCamera camera = smallCamera();
  const float d = 2.0f;
  const DepthImage depth(kWidth, kHeight, d);
  DepthConversionStats stats;
  const PointCloud cloud =
      depthToPointCloud(depth, camera, nullptr, DepthConversionConfig{}, &stats);
  ASSERT_EQ(cloud.size(), static_cast<size_t>(kWidth * kHeight));
  EXPECT_FALSE(cloud.hasColors());
  EXPECT_EQ(stats.valid, static_cast<size_t>(kWidth * kHeight));
  EXPECT_EQ(stats.non_finite + stats.non_positive + stats.out_of_range, 0u);
  size_t i = 0;
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u, ++i) {
      const Eigen::Vector3f& p = cloud.points[i];
      EXPECT_EQ(p.z(), d);
      // Analytic: x = (u - cx) / fx * d, y = (v - cy) / fy * d.
      EXPECT_FLOAT_EQ(p.x(), static_cast<float>((u - 3.5) / 10.0 * 2.0)) << u << "," << v;
      EXPECT_FLOAT_EQ(p.y(), static_cast<float>((v - 2.5) / 12.0 * 2.0)) << u << "," << v;
      // Same arithmetic as the camera model.
      const Eigen::Vector3d q = camera.backProject(Eigen::Vector2d(u, v), d);
      EXPECT_EQ(p, q.cast<float>());
    }
  }
  // Spot check in closed form: pixel (0, 0) -> (-0.7, -5/12).
  EXPECT_NEAR(cloud.points[0].x(), -0.7f, 1e-7f);
  EXPECT_NEAR(cloud.points[0].y(), -5.0f / 12.0f, 1e-7f);
}

TEST(DepthToPointCloud, PointZEqualsDepthForVaryingDepths) {
  const PinholeCamera camera = smallCamera();
  DepthImage depth(kWidth, kHeight);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) depth(u, v) = 0.3f + 0.0913f * static_cast<float>(u + 8 * v);
  }
  DepthConversionConfig config;
  config.max_depth_m = 100.0f;
  const PointCloud cloud = depthToPointCloud(depth, camera, nullptr, config);
  ASSERT_EQ(cloud.size(), depth.data.size());
  for (size_t i = 0; i < cloud.size(); ++i) EXPECT_EQ(cloud.points[i].z(), depth.data[i]);
}

TEST(DepthToPointCloud, CountsInvalidPixels) {
  const PinholeCamera camera = smallCamera();
  DepthImage depth(kWidth, kHeight, 1.0f);
  const float inf = std::numeric_limits<float>::infinity();
  depth(0, 0) = std::numeric_limits<float>::quiet_NaN();
  depth(1, 0) = inf;
  depth(2, 0) = -inf;
  depth(3, 0) = 0.0f;
  depth(4, 0) = -1.0f;
  depth(5, 0) = -0.0f;
  depth(6, 0) = 0.05f;  // below min 0.1
  depth(7, 0) = 5.01f;  // above max 5.0
  depth(0, 1) = 0.1f;   // exactly min: kept
  depth(1, 1) = 5.0f;   // exactly max: kept
  DepthConversionStats stats;
  stats.valid = 999;  // reset by the call
  const PointCloud cloud =
      depthToPointCloud(depth, camera, nullptr, DepthConversionConfig{}, &stats);
  EXPECT_EQ(stats.non_finite, 3u);
  EXPECT_EQ(stats.non_positive, 3u);
  EXPECT_EQ(stats.out_of_range, 2u);
  EXPECT_EQ(stats.valid, static_cast<size_t>(kWidth * kHeight - 8));
  EXPECT_EQ(cloud.size(), stats.valid);
  // The first kept point is pixel (0, 1) with depth exactly min.
  EXPECT_EQ(cloud.points[0].z(), 0.1f);
  EXPECT_EQ(cloud.points[1].z(), 5.0f);
  for (const Eigen::Vector3f& p : cloud.points) EXPECT_TRUE(p.allFinite());
}

TEST(DepthToPointCloud, AllInvalidGivesEmptyCloud) {
  const PinholeCamera camera = smallCamera();
  const DepthImage depth(kWidth, kHeight, 0.0f);
  DepthConversionStats stats;
  const ColorImage colors = gradientColors(kWidth, kHeight);
  const PointCloud cloud =
      depthToPointCloud(depth, camera, &colors, DepthConversionConfig{}, &stats);
  EXPECT_EQ(cloud.size(), 0u);
  EXPECT_EQ(cloud.colors.size(), 0u);
  EXPECT_EQ(stats.non_positive, static_cast<size_t>(kWidth * kHeight));
}

TEST(DepthToPointCloud, StrideSamplesEveryStrideThRowAndColumn) {
  const PinholeCamera camera = smallCamera();
  const DepthImage depth(kWidth, kHeight, 1.0f);
  const ColorImage colors = gradientColors(kWidth, kHeight);
  for (int stride : {1, 2, 3, 5, 100}) {
    DepthConversionConfig config;
    config.stride = stride;
    DepthConversionStats stats;
    const PointCloud cloud = depthToPointCloud(depth, camera, &colors, config, &stats);
    const int nu = (kWidth + stride - 1) / stride;
    const int nv = (kHeight + stride - 1) / stride;
    ASSERT_EQ(cloud.size(), static_cast<size_t>(nu * nv)) << "stride " << stride;
    EXPECT_EQ(stats.valid, cloud.size());
    ASSERT_EQ(cloud.colors.size(), cloud.size());
    size_t i = 0;
    for (int v = 0; v < kHeight; v += stride) {
      for (int u = 0; u < kWidth; u += stride, ++i) {
        EXPECT_EQ(cloud.colors[i], colorAt(u, v));
        EXPECT_EQ(cloud.points[i], camera.backProject(Eigen::Vector2d(u, v), 1.0).cast<float>());
      }
    }
  }
}

TEST(DepthToPointCloud, StrideCountsOnlySampledPixels) {
  const PinholeCamera camera = smallCamera();
  DepthImage depth(kWidth, kHeight, 1.0f);
  depth(1, 1) = 0.0f;  // not sampled with stride 2
  depth(2, 2) = 0.0f;  // sampled
  DepthConversionConfig config;
  config.stride = 2;
  DepthConversionStats stats;
  const PointCloud cloud = depthToPointCloud(depth, camera, nullptr, config, &stats);
  EXPECT_EQ(stats.non_positive, 1u);
  EXPECT_EQ(stats.valid, 4u * 3u - 1u);
  EXPECT_EQ(cloud.size(), stats.valid);
}

TEST(DepthToPointCloud, ColorsFollowKeptPixels) {
  const PinholeCamera camera = smallCamera();
  DepthImage depth(kWidth, kHeight, 0.0f);
  depth(2, 1) = 1.0f;
  depth(5, 4) = 2.0f;
  const ColorImage colors = gradientColors(kWidth, kHeight);
  const PointCloud cloud = depthToPointCloud(depth, camera, &colors, DepthConversionConfig{});
  ASSERT_EQ(cloud.size(), 2u);
  ASSERT_TRUE(cloud.hasColors());
  EXPECT_EQ(cloud.colors[0], colorAt(2, 1));
  EXPECT_EQ(cloud.colors[1], colorAt(5, 4));
}

TEST(DepthToPointCloud, ColorSizeMismatchThrows) {
  const PinholeCamera camera = smallCamera();
  const DepthImage depth(kWidth, kHeight, 1.0f);
  const ColorImage wrong(kWidth, kHeight + 1);
  EXPECT_THROW(depthToPointCloud(depth, camera, &wrong, DepthConversionConfig{}),
               std::invalid_argument);
  const ColorImage empty;
  EXPECT_THROW(depthToPointCloud(depth, camera, &empty, DepthConversionConfig{}),
               std::invalid_argument);
}

TEST(DepthToPointCloud, DepthSizeMismatchWithCameraThrows) {
  const PinholeCamera camera = smallCamera();
  const DepthImage depth(kWidth + 1, kHeight, 1.0f);
  EXPECT_THROW(depthToPointCloud(depth, camera, nullptr, DepthConversionConfig{}),
               std::invalid_argument);
}

TEST(DepthToPointCloud, InvalidConfigThrows) {
  const PinholeCamera camera = smallCamera();
  const DepthImage depth(kWidth, kHeight, 1.0f);
  DepthConversionConfig config;
  config.stride = 0;
  try {
    depthToPointCloud(depth, camera, nullptr, config);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("stride"), std::string::npos) << e.what();
  }
}

TEST(DepthConversionConfig, ValidationMessagesNameTheField) {
  EXPECT_EQ(DepthConversionConfig{}.validate(), "");
  DepthConversionConfig c;
  c.min_depth_m = -1.0f;
  EXPECT_EQ(c.validate(), "min_depth_m must be finite and > 0, got -1");
  c = {};
  c.min_depth_m = 0.0f;
  EXPECT_NE(c.validate().find("min_depth_m"), std::string::npos);
  c = {};
  c.min_depth_m = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(c.validate().find("min_depth_m"), std::string::npos);
  c = {};
  c.max_depth_m = 0.05f;
  EXPECT_EQ(c.validate(), "max_depth_m must be finite and > min_depth_m (0.1), got 0.05");
  c = {};
  c.max_depth_m = 0.1f;  // equal to min
  EXPECT_NE(c.validate().find("max_depth_m"), std::string::npos);
  c = {};
  c.max_depth_m = std::numeric_limits<float>::infinity();
  EXPECT_NE(c.validate().find("max_depth_m"), std::string::npos);
  c = {};
  c.stride = 0;
  EXPECT_EQ(c.validate(), "stride must be >= 1, got 0");
  c.stride = -3;
  EXPECT_EQ(c.validate(), "stride must be >= 1, got -3");
}

}  // namespace
}  // namespace cblox
