#include "core/esdf/esdf_query.h"

#include <cmath>

#include <gtest/gtest.h>

#include "core/esdf/esdf_integrator.h"
#include "test/esdf/esdf_test_scenes.h"

namespace cblox {
namespace {

constexpr float kVoxel = 0.05f;

LayerConfig geometry() {
  LayerConfig config;
  config.voxel_size = kVoxel;
  config.voxels_per_side = 8;
  return config;
}

class EsdfQueryTest : public ::testing::Test {
 protected:
  // A wall x < 0.31 observed over [-0.4, 1.6] x [-0.4, 0.4]^2; its interior deeper than the
  // truncation is unobserved.
  void SetUp() override {
    esdf_test::writeTsdf(&tsdf_, esdf_test::planeX(0.31f), {-0.4f, -0.4f, -0.4f},
                         {1.6f, 0.4f, 0.4f}, 0.15f);
    EsdfConfig config;
    config.max_distance_m = 1.0f;
    EsdfIntegrator(config).update(tsdf_, &esdf_);
  }
  TsdfLayer tsdf_{geometry()};
  EsdfLayer esdf_{geometry(), 1.0f};
};

TEST_F(EsdfQueryTest, InterpolationIsExactOnAPlaneWithAUnitGradient) {
  for (const float x : {0.3361f, 0.52f, 0.777f, 1.1234f}) {
    const Eigen::Vector3f p(x, 0.0123f, -0.071f);
    const DistanceSample s = queryInterpolated(esdf_, p);
    ASSERT_EQ(s.state, VoxelState::kFree) << x;
    ASSERT_TRUE(s.has_gradient);
    EXPECT_NEAR(s.distance, x - 0.31f, 1e-5f);
    EXPECT_NEAR(s.gradient.x(), 1.0f, 1e-4f);
    EXPECT_NEAR(s.gradient.y(), 0.0f, 1e-4f);
    EXPECT_NEAR(s.gradient.z(), 0.0f, 1e-4f);
  }
  // Across the surface the TSDF values inside continue the same line: negative, occupied.
  const DistanceSample inside = queryInterpolated(esdf_, {0.28f, 0.0f, 0.0f});
  EXPECT_EQ(inside.state, VoxelState::kOccupied);
  EXPECT_NEAR(inside.distance, -0.03f, 1e-5f);
}

TEST_F(EsdfQueryTest, NearestAnswersTheVoxelThatHoldsThePoint) {
  const DistanceSample s = queryNearest(esdf_, {0.52f, 0.0f, 0.0f});  // centre 0.525
  EXPECT_EQ(s.state, VoxelState::kFree);
  EXPECT_NEAR(s.distance, 0.525f - 0.31f, 1e-5f);
  EXPECT_FALSE(s.has_gradient);
  EXPECT_TRUE(std::isnan(s.gradient.x()));
  // Beyond the cap: exactly the cap ("at least this far").
  EXPECT_EQ(queryNearest(esdf_, {1.5f, 0.0f, 0.0f}).distance, 1.0f);
}

TEST_F(EsdfQueryTest, UnknownSpaceIsAnAnswerWithoutADistance) {
  // Deep inside the wall (never observed) and outside every block.
  for (const Eigen::Vector3f& p : {Eigen::Vector3f(-0.2f, 0.0f, 0.0f),
                                   Eigen::Vector3f(5.0f, 5.0f, 5.0f)}) {
    for (const DistanceSample& s : {queryNearest(esdf_, p), queryInterpolated(esdf_, p)}) {
      EXPECT_EQ(s.state, VoxelState::kUnknown);
      EXPECT_TRUE(std::isnan(s.distance));
    }
  }
  // Outside every block nothing is known, not even a bound.
  const DistanceSample outside = queryInterpolated(esdf_, {5.0f, 5.0f, 5.0f});
  EXPECT_TRUE(std::isnan(outside.bound));
  EXPECT_FALSE(outside.has_gradient);
  // Inside the wall the wave carried the nearest occupied voxel (centre 0.175, counted at
  // -1 voxel): the voxel centred at -0.175 holds 0.35 - 0.05, the one at -0.225 0.40 - 0.05;
  // -0.2 lies halfway. The bound decreases towards the surface.
  const DistanceSample nearest = queryNearest(esdf_, {-0.2f, 0.0f, 0.0f});
  EXPECT_NEAR(nearest.bound, 0.30f, 1e-5f);
  EXPECT_FALSE(nearest.has_gradient);
  const DistanceSample inside = queryInterpolated(esdf_, {-0.2f, 0.0f, 0.0f});
  EXPECT_NEAR(inside.bound, 0.325f, 1e-5f);
  ASSERT_TRUE(inside.has_gradient);
  EXPECT_NEAR(inside.gradient.x(), -1.0f, 1e-4f);
  EXPECT_NEAR(inside.gradient.y(), 0.0f, 1e-4f);
  // Observed answers have no bound.
  EXPECT_TRUE(std::isnan(queryInterpolated(esdf_, {0.52f, 0.0f, 0.0f}).bound));
  // Interpolation next to unknown space falls back to the nearest voxel, without gradient.
  const DistanceSample edge = queryInterpolated(esdf_, {0.16f, 0.0f, 0.0f});
  EXPECT_FALSE(edge.has_gradient);
  EXPECT_EQ(edge.state, VoxelState::kOccupied);
  EXPECT_NEAR(edge.distance, 0.175f - 0.31f, 1e-5f);
  // Non-finite points are unknown, not a crash.
  EXPECT_EQ(queryInterpolated(esdf_, {NAN, 0.0f, 0.0f}).state, VoxelState::kUnknown);
  EXPECT_EQ(queryNearest(esdf_, {INFINITY, 0.0f, 0.0f}).state, VoxelState::kUnknown);
}

TEST(EsdfQueryMarginTest, LowersByTheMarginThenLessOverOneVoxel) {
  // Margin 0.5 at 0.1 m voxels: the whole 0.05 m up to 0.15 m, tapering to nothing at 0.25 m.
  double slope = 0.0;
  EXPECT_DOUBLE_EQ(lowerBesideSurface(0.02, 0.1, 0.5, &slope), 0.0);  // held at 0
  EXPECT_DOUBLE_EQ(slope, 1.0);
  EXPECT_DOUBLE_EQ(lowerBesideSurface(0.1, 0.1, 0.5, &slope), 0.05);
  EXPECT_DOUBLE_EQ(lowerBesideSurface(0.15, 0.1, 0.5, &slope), 0.1);  // (1 + m) voxels -> 1
  EXPECT_DOUBLE_EQ(slope, 1.0);
  EXPECT_NEAR(lowerBesideSurface(0.2, 0.1, 0.5, &slope), 0.175, 1e-15);
  EXPECT_DOUBLE_EQ(slope, 1.5);
  EXPECT_DOUBLE_EQ(lowerBesideSurface(0.25, 0.1, 0.5, &slope), 0.25);
  EXPECT_DOUBLE_EQ(slope, 1.0);
  EXPECT_DOUBLE_EQ(lowerBesideSurface(1.7, 0.1, 0.5), 1.7);
  // Continuous and increasing across the taper's ends.
  EXPECT_NEAR(lowerBesideSurface(0.15 + 1e-9, 0.1, 0.5), 0.1, 1e-8);
  EXPECT_NEAR(lowerBesideSurface(0.25 - 1e-9, 0.1, 0.5), 0.25, 1e-8);
  // No margin: the distance itself.
  EXPECT_DOUBLE_EQ(lowerBesideSurface(0.12, 0.1, 0.0, &slope), 0.12);
  EXPECT_DOUBLE_EQ(slope, 1.0);
  // The config refuses a margin outside [0, 1].
  EsdfConfig config;
  EXPECT_TRUE(config.validate().empty());
  config.surface_margin_voxels = 1.5f;
  EXPECT_NE(config.validate().find("surface_margin_voxels"), std::string::npos);
  config.surface_margin_voxels = NAN;
  EXPECT_NE(config.validate().find("surface_margin_voxels"), std::string::npos);
}

TEST(EsdfVoxelTest, StatesHaveNames) {
  EXPECT_STREQ(voxelStateName(VoxelState::kUnknown), "unknown");
  EXPECT_STREQ(voxelStateName(VoxelState::kFree), "free");
  EXPECT_STREQ(voxelStateName(VoxelState::kOccupied), "occupied");
}

TEST(EsdfLayerTest, MemoryIsCountedPerBlock) {
  EsdfLayer layer(geometry(), 2.0f);
  const size_t empty = layer.memoryBytes();
  layer.allocateBlock(BlockIndex(1, 2, 3));
  layer.allocateBlock(BlockIndex(-1, 0, 0));
  EXPECT_GE(layer.memoryBytes(), empty + 2 * layer.bytesPerBlock());
  EXPECT_EQ(layer.bytesPerBlock(), sizeof(EsdfBlock) + 512 * sizeof(EsdfVoxel));
  // A new block is unknown at the cap, without a site.
  const EsdfVoxel& v = layer.getBlock(BlockIndex(1, 2, 3))->voxel(7);
  EXPECT_EQ(v.state, VoxelState::kUnknown);
  EXPECT_EQ(v.own_distance, 2.0f);
  EXPECT_FALSE(v.hasSite());
  EXPECT_TRUE(layer.removeBlock(BlockIndex(1, 2, 3)));
  EXPECT_FALSE(layer.removeBlock(BlockIndex(1, 2, 3)));
  EXPECT_EQ(layer.numBlocks(), 1u);
}

}  // namespace
}  // namespace cblox
