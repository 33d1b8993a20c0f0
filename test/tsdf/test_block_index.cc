#include "core/tsdf/block_index.h"

#include <gtest/gtest.h>

namespace cblox {
namespace {

TEST(BlockIndex, PackUnpackRoundTripsOverTheWholeRange) {
  const int values[] = {kGridIndexMin, kGridIndexMin + 1, -1000, -1, 0, 1, 777, kGridIndexMax};
  for (int x : values) {
    for (int y : values) {
      for (int z : values) {
        const GridIndex index(x, y, z);
        ASSERT_EQ(unpackGridIndex(packGridIndex(index)), index) << index.transpose();
      }
    }
  }
  EXPECT_NE(packGridIndex({1, 0, 0}), packGridIndex({0, 1, 0}));
  EXPECT_LT(packGridIndex({kGridIndexMax, kGridIndexMax, kGridIndexMax}), uint64_t{1} << 63);
}

TEST(BlockIndex, RangeCheck) {
  EXPECT_TRUE(gridIndexInRange({kGridIndexMax, kGridIndexMin, 0}));
  EXPECT_FALSE(gridIndexInRange({kGridIndexMax + 1, 0, 0}));
  EXPECT_FALSE(gridIndexInRange({0, kGridIndexMin - 1, 0}));
}

TEST(BlockIndex, GridIndexFromPointFloorsNegativeCoordinates) {
  EXPECT_EQ(gridIndexFromPoint({0.01f, -0.01f, 0.0f}, 50.0f), GridIndex(0, -1, 0));
  EXPECT_EQ(gridIndexFromPoint({0.039f, -0.041f, 1.0f}, 50.0f), GridIndex(1, -3, 50));
}

TEST(BlockIndex, SplitGlobalVoxelIndex) {
  BlockIndex block;
  GridIndex local;
  splitGlobalVoxelIndex({17, -1, -16}, 3, &block, &local);  // 8 voxels per side
  EXPECT_EQ(block, BlockIndex(2, -1, -2));
  EXPECT_EQ(local, GridIndex(1, 7, 0));
  splitGlobalVoxelIndex({-17, 0, 15}, 4, &block, &local);  // 16 voxels per side
  EXPECT_EQ(block, BlockIndex(-2, 0, 0));
  EXPECT_EQ(local, GridIndex(15, 0, 15));
}

}  // namespace
}  // namespace cblox
