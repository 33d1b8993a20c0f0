#include "core/tsdf/tsdf_interpolator.h"

#include <gtest/gtest.h>

namespace cblox {
namespace {

// Fills every voxel of a 2x2x2-block region with a linear field f(p) = a.p + b, which
// trilinear interpolation reproduces exactly.
void fillLinear(TsdfLayer* layer, const Eigen::Vector3f& a, float b) {
  for (int x = -1; x <= 0; ++x) {
    for (int y = -1; y <= 0; ++y) {
      for (int z = -1; z <= 0; ++z) {
        Block* block = layer->allocateBlock(BlockIndex(x, y, z));
        for (int i = 0; i < block->numVoxels(); ++i) {
          const Eigen::Vector3f c = block->voxelCenter(block->localIndex(i));
          block->voxel(i).distance = a.dot(c) + b;
          block->voxel(i).weight = 1.0f;
          block->voxel(i).color = Color{100, 150, 200};
        }
      }
    }
  }
}

TEST(TsdfInterpolator, ReproducesLinearFieldsExactlyAcrossBlockBorders) {
  TsdfLayer layer(LayerConfig{0.05f, 8});
  const Eigen::Vector3f a(0.3f, -0.5f, 0.8f);
  fillLinear(&layer, a, 0.1f);
  const TsdfInterpolator interpolator(layer);
  for (const Eigen::Vector3f& p :
       {Eigen::Vector3f(0.0f, 0.0f, 0.0f), Eigen::Vector3f(-0.013f, 0.1f, -0.2f),
        Eigen::Vector3f(0.17f, -0.3f, 0.02f)}) {
    float distance = 0.0f;
    Color color;
    ASSERT_TRUE(interpolator.getInterpolatedDistance(p, &distance, &color)) << p.transpose();
    EXPECT_NEAR(distance, a.dot(p) + 0.1f, 1e-6f);
    EXPECT_EQ(color, (Color{100, 150, 200}));
  }
  // At a voxel centre nearest and interpolated values coincide.
  const Eigen::Vector3f centre(0.125f, 0.025f, -0.075f);
  float nearest = 0.0f, interpolated = 0.0f;
  ASSERT_TRUE(interpolator.getNearestDistance(centre, &nearest));
  ASSERT_TRUE(interpolator.getInterpolatedDistance(centre, &interpolated));
  EXPECT_NEAR(nearest, interpolated, 1e-6f);
}

TEST(TsdfInterpolator, FailsWithoutAllEightObservedNeighbours) {
  TsdfLayer layer(LayerConfig{0.05f, 8});
  fillLinear(&layer, Eigen::Vector3f(1, 0, 0), 0.0f);
  const TsdfInterpolator interpolator(layer);
  float distance = 0.0f;
  // Outside the allocated region (x > 0.4 - half a voxel): a neighbour block is missing.
  EXPECT_FALSE(interpolator.getInterpolatedDistance(Eigen::Vector3f(0.39f, 0.0f, 0.0f), &distance));
  // An unobserved corner voxel also fails.
  layer.getVoxel(GlobalVoxelIndex(0, 0, 0))->weight = 0.0f;
  EXPECT_FALSE(
      interpolator.getInterpolatedDistance(Eigen::Vector3f(0.03f, 0.03f, 0.03f), &distance));
  EXPECT_FALSE(interpolator.getNearestDistance(Eigen::Vector3f(0.01f, 0.01f, 0.01f), &distance));
}

}  // namespace
}  // namespace cblox
