#include "core/tsdf/tsdf_layer.h"

#include <stdexcept>

#include <gtest/gtest.h>

namespace cblox {
namespace {

TEST(TsdfLayer, AllocateFindRemove) {
  TsdfLayer layer(LayerConfig{0.02f, 8});
  EXPECT_FLOAT_EQ(layer.blockSize(), 0.16f);
  EXPECT_EQ(layer.getBlock(BlockIndex(1, 2, 3)), nullptr);
  bool is_new = false;
  Block* block = layer.allocateBlock(BlockIndex(1, 2, 3), &is_new);
  ASSERT_NE(block, nullptr);
  EXPECT_TRUE(is_new);
  EXPECT_EQ(layer.allocateBlock(BlockIndex(1, 2, 3), &is_new), block);
  EXPECT_FALSE(is_new);
  EXPECT_EQ(layer.getBlock(BlockIndex(1, 2, 3)), block);
  EXPECT_EQ(layer.numBlocks(), 1u);
  layer.allocateBlock(BlockIndex(-1, 0, 0));
  EXPECT_EQ(layer.numBlocks(), 2u);
  EXPECT_TRUE(layer.removeBlock(BlockIndex(1, 2, 3)));
  EXPECT_FALSE(layer.removeBlock(BlockIndex(1, 2, 3)));
  EXPECT_EQ(layer.blockIndices(), std::vector<BlockIndex>{BlockIndex(-1, 0, 0)});
  layer.clear();
  EXPECT_EQ(layer.numBlocks(), 0u);
}

TEST(TsdfLayer, OutOfRangeIndicesAreRejected) {
  TsdfLayer layer(LayerConfig{0.02f, 8});
  EXPECT_THROW(layer.allocateBlock(BlockIndex(kGridIndexMax + 1, 0, 0)), std::out_of_range);
  EXPECT_EQ(layer.getBlock(BlockIndex(0, kGridIndexMin - 1, 0)), nullptr);
  EXPECT_FALSE(layer.removeBlock(BlockIndex(0, 0, kGridIndexMax + 1)));
}

TEST(TsdfLayer, VoxelLookupByPointAndGlobalIndex) {
  TsdfLayer layer(LayerConfig{0.1f, 4});
  Block* block = layer.allocateBlock(BlockIndex(-1, 0, 0));
  block->voxel({3, 1, 2}).distance = 0.25f;
  block->voxel({3, 1, 2}).weight = 2.0f;
  // Voxel (3,1,2) of block (-1,0,0) is global voxel (-1,1,2), spanning x in [-0.1, 0).
  const TsdfVoxel* voxel = layer.getVoxelAtPoint(Eigen::Vector3f(-0.05f, 0.15f, 0.25f));
  ASSERT_NE(voxel, nullptr);
  EXPECT_FLOAT_EQ(voxel->distance, 0.25f);
  EXPECT_EQ(layer.getVoxel(GlobalVoxelIndex(-1, 1, 2)), voxel);
  EXPECT_EQ(layer.getVoxelAtPoint(Eigen::Vector3f(0.05f, 0.15f, 0.25f)), nullptr);
  EXPECT_TRUE(layer.globalVoxelCenter({-1, 1, 2}).isApprox(Eigen::Vector3f(-0.05f, 0.15f, 0.25f)));
}

TEST(TsdfLayer, MemoryAccountingGrowsWithBlocks) {
  TsdfLayer layer(LayerConfig{0.02f, 8});
  const size_t empty = layer.memoryBytes();
  for (int i = 0; i < 100; ++i) layer.allocateBlock(BlockIndex(i, 0, 0));
  const size_t voxel_bytes = 100 * 512 * sizeof(TsdfVoxel);
  EXPECT_GE(layer.memoryBytes(), empty + voxel_bytes);
  EXPECT_LT(layer.memoryBytes(), empty + voxel_bytes + 100 * 1024);
}

TEST(TsdfLayer, InvalidConfigThrowsNamingTheField) {
  try {
    TsdfLayer layer(LayerConfig{0.02f, 10});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("voxels_per_side"), std::string::npos);
  }
}

}  // namespace
}  // namespace cblox
