#include "core/integrator/tsdf_voxel_update.h"

#include <gtest/gtest.h>

namespace cblox {
namespace {

IntegratorConfig constantWeightConfig() {
  IntegratorConfig config;
  config.truncation_distance_m = 0.08f;
  config.weight_model = WeightModel::kConstant;
  config.use_weight_dropoff = false;
  return config;
}

TEST(TsdfVoxelUpdater, FirstMeasurementIsStoredExactly) {
  const TsdfVoxelUpdater updater(constantWeightConfig(), 0.02f);
  TsdfVoxel voxel;
  ASSERT_TRUE(updater.update(0.031f, 1.0f, Color{10, 20, 30}, &voxel));
  EXPECT_FLOAT_EQ(voxel.distance, 0.031f);
  EXPECT_FLOAT_EQ(voxel.weight, 1.0f);
  EXPECT_EQ(voxel.color, (Color{10, 20, 30}));
}

TEST(TsdfVoxelUpdater, WeightedAverageAndColourBlend) {
  const TsdfVoxelUpdater updater(constantWeightConfig(), 0.02f);
  TsdfVoxel voxel;
  updater.update(0.02f, 1.0f, Color{0, 0, 0}, &voxel);
  updater.update(-0.04f, 3.0f, Color{200, 100, 40}, &voxel);
  EXPECT_FLOAT_EQ(voxel.distance, (0.02f * 1.0f - 0.04f * 3.0f) / 4.0f);
  EXPECT_FLOAT_EQ(voxel.weight, 4.0f);
  EXPECT_EQ(voxel.color, (Color{150, 75, 30}));
}

TEST(TsdfVoxelUpdater, ClampsToTruncationAndSkipsFarBehind) {
  const TsdfVoxelUpdater updater(constantWeightConfig(), 0.02f);
  TsdfVoxel voxel;
  ASSERT_TRUE(updater.update(1.5f, 1.0f, Color{}, &voxel));  // free space in front
  EXPECT_FLOAT_EQ(voxel.distance, 0.08f);
  TsdfVoxel behind;
  EXPECT_FALSE(updater.update(-0.0801f, 1.0f, Color{}, &behind));
  EXPECT_FLOAT_EQ(behind.weight, 0.0f);
}

TEST(TsdfVoxelUpdater, WeightSaturates) {
  IntegratorConfig config = constantWeightConfig();
  config.max_weight = 2.5f;
  const TsdfVoxelUpdater updater(config, 0.02f);
  TsdfVoxel voxel;
  for (int i = 0; i < 10; ++i) updater.update(0.01f, 1.0f, Color{}, &voxel);
  EXPECT_FLOAT_EQ(voxel.weight, 2.5f);
  EXPECT_FLOAT_EQ(voxel.distance, 0.01f);
}

TEST(TsdfVoxelUpdater, InverseSquareWeightAndDropoff) {
  IntegratorConfig config = constantWeightConfig();
  config.weight_model = WeightModel::kInverseSquare;
  config.use_weight_dropoff = true;
  const TsdfVoxelUpdater updater(config, 0.02f);
  EXPECT_FLOAT_EQ(updater.measurementWeight(2.0f), 0.25f);
  // Between -voxel and -truncation the weight falls linearly to 0:
  // w * (trunc + sdf) / (trunc - voxel) = 1 * (0.08 - 0.05) / 0.06 = 0.5.
  TsdfVoxel voxel;
  ASSERT_TRUE(updater.update(-0.05f, 1.0f, Color{}, &voxel));
  EXPECT_NEAR(voxel.weight, 0.5f, 1e-6f);
  TsdfVoxel in_front;
  updater.update(-0.015f, 1.0f, Color{}, &in_front);  // within one voxel: full weight
  EXPECT_FLOAT_EQ(in_front.weight, 1.0f);
}

}  // namespace
}  // namespace cblox
