#include "core/tsdf/block.h"

#include <gtest/gtest.h>

namespace cblox {
namespace {

TEST(Block, GeometryAndIndexing) {
  const Block block(BlockIndex(1, -2, 0), 8, 0.05f);
  EXPECT_EQ(block.numVoxels(), 512);
  EXPECT_EQ(block.voxelsPerSideLog2(), 3);
  EXPECT_FLOAT_EQ(block.blockSize(), 0.4f);
  EXPECT_TRUE(block.origin().isApprox(Eigen::Vector3f(0.4f, -0.8f, 0.0f)));
  EXPECT_TRUE(block.voxelCenter({0, 0, 0}).isApprox(Eigen::Vector3f(0.425f, -0.775f, 0.025f)));
  EXPECT_TRUE(block.voxelCenter({7, 7, 7}).isApprox(Eigen::Vector3f(0.775f, -0.425f, 0.375f)));
  for (int i = 0; i < block.numVoxels(); ++i) ASSERT_EQ(block.linearIndex(block.localIndex(i)), i);
  EXPECT_EQ(block.linearIndex({1, 2, 3}), 1 + 8 * 2 + 64 * 3);
}

TEST(Block, StartsUnobservedAndCountsObservedVoxels) {
  Block block(BlockIndex(0, 0, 0), 16, 0.02f);
  EXPECT_EQ(block.countObservedVoxels(), 0);
  EXPECT_FALSE(block.updated());
  block.voxel({3, 4, 5}).weight = 1.0f;
  block.voxel(0).weight = 0.5f;
  EXPECT_EQ(block.countObservedVoxels(), 2);
  EXPECT_EQ(block.changeCount(), 0u);
  block.setUpdated(true);
  EXPECT_TRUE(block.updated());
  EXPECT_EQ(block.changeCount(), 1u);
  // Clearing the flag (the mesher consumed the change) keeps the count; each later change
  // advances it again.
  block.setUpdated(false);
  EXPECT_FALSE(block.updated());
  EXPECT_EQ(block.changeCount(), 1u);
  block.setUpdated(true);
  EXPECT_EQ(block.changeCount(), 2u);
  EXPECT_EQ(block.memoryBytes(), sizeof(Block) + 4096 * sizeof(TsdfVoxel));
}

}  // namespace
}  // namespace cblox
