#include "core/integrator/block_cube_set.h"

#include <atomic>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

TEST(BlockCubeSet, EveryBlockOfTheCubeHasItsOwnBitAndIsInsertedOnce) {
  BlockCubeSet set(1u << 12);
  ASSERT_TRUE(set.reset(BlockIndex(-5, 7, 100), 2));  // 5^3 blocks: [-7, -3] x [5, 9] x [98, 102]
  std::vector<bool> seen(125, false);
  for (int z = 98; z <= 102; ++z) {
    for (int y = 5; y <= 9; ++y) {
      for (int x = -7; x <= -3; ++x) {
        const size_t bit = set.bitOf(x, y, z);
        ASSERT_LT(bit, 125u);
        EXPECT_FALSE(seen[bit]) << x << " " << y << " " << z;
        seen[bit] = true;
        EXPECT_FALSE(set.contains(bit));
        EXPECT_TRUE(set.insert(bit));
        EXPECT_TRUE(set.contains(bit));
        EXPECT_FALSE(set.insert(bit));
      }
    }
  }
  EXPECT_EQ(set.bitOf(-7, 5, 98), 0u);
  EXPECT_EQ(set.bitOf(-3, 9, 102), 124u);
  EXPECT_EQ(set.side(), 5u);
  EXPECT_EQ(set.bitOf(-6, 8, 99), set.bitOf(-6, 7, 99) + set.side());
  EXPECT_EQ(set.bitOf(-6, 8, 100), set.bitOf(-6, 8, 99) + set.side() * set.side());
  // reset() empties the set, at a new place.
  ASSERT_TRUE(set.reset(BlockIndex(0, 0, 0), 2));
  for (size_t bit = 0; bit < 125; ++bit) EXPECT_FALSE(set.contains(bit));
}

TEST(BlockCubeSet, RunReadsConsecutiveBitsAcrossWordBoundaries) {
  BlockCubeSet set(1u << 12);
  ASSERT_TRUE(set.reset(BlockIndex(0, 0, 0), 4));  // 9^3 = 729 bits, 12 words
  const std::vector<size_t> members = {0, 3, 63, 64, 65, 127, 128, 200, 700, 728};
  for (const size_t bit : members) ASSERT_TRUE(set.insert(bit));
  const auto expected = [&](size_t first, int n) {
    uint64_t word = 0;
    for (const size_t bit : members) {
      if (bit >= first && bit < first + static_cast<size_t>(n))
        word |= uint64_t{1} << (bit - first);
    }
    return word;
  };
  for (const auto& [first, n] : std::vector<std::pair<size_t, int>>{{0, 1},
                                                                    {0, 4},
                                                                    {0, 64},
                                                                    {1, 64},
                                                                    {60, 8},
                                                                    {63, 2},
                                                                    {64, 64},
                                                                    {100, 29},
                                                                    {127, 64},
                                                                    {700, 29},
                                                                    {665, 64},
                                                                    {728, 1}}) {
    EXPECT_EQ(set.run(first, n), expected(first, n)) << first << " " << n;
  }
  EXPECT_EQ(set.run(0, 64), (uint64_t{1} << 0) | (uint64_t{1} << 3) | (uint64_t{1} << 63));
  EXPECT_EQ(set.run(63, 3), 7u);  // bits 63, 64, 65: one from each of two words
  EXPECT_EQ(set.run(4, 59), 0u);
}

TEST(BlockCubeSet, CoversOnlyBoxesInsideTheCube) {
  BlockCubeSet set(1u << 12);
  ASSERT_TRUE(set.reset(BlockIndex(0, 0, 0), 3));  // [-3, 3] per axis
  EXPECT_TRUE(set.covers(BlockIndex(-3, -3, -3), BlockIndex(3, 3, 3)));
  EXPECT_TRUE(set.covers(BlockIndex(0, 1, 2), BlockIndex(0, 1, 2)));
  EXPECT_FALSE(set.covers(BlockIndex(-4, 0, 0), BlockIndex(0, 0, 0)));
  EXPECT_FALSE(set.covers(BlockIndex(0, 0, 0), BlockIndex(0, 4, 0)));
  EXPECT_FALSE(set.covers(BlockIndex(0, 0, -4), BlockIndex(0, 0, 3)));
  EXPECT_FALSE(set.covers(BlockIndex(0, 0, 0), BlockIndex(0, 0, 4)));
}

TEST(BlockCubeSet, ACubeTooLargeOrNegativeLeavesTheSetUnusable) {
  BlockCubeSet set(1000);                          // 10^3 fits, 11^3 does not
  EXPECT_TRUE(set.reset(BlockIndex(0, 0, 0), 4));  // 9^3 = 729
  EXPECT_TRUE(set.covers(BlockIndex(0, 0, 0), BlockIndex(1, 1, 1)));
  EXPECT_FALSE(set.reset(BlockIndex(0, 0, 0), 5));  // 11^3 = 1331
  EXPECT_FALSE(set.covers(BlockIndex(0, 0, 0), BlockIndex(0, 0, 0)));
  EXPECT_FALSE(set.reset(BlockIndex(0, 0, 0), -1));
  EXPECT_FALSE(set.covers(BlockIndex(0, 0, 0), BlockIndex(0, 0, 0)));
}

TEST(BlockCubeSet, ConcurrentInsertsOfOneBlockGiveExactlyOneTrue) {
  BlockCubeSet set(1u << 16);
  for (int round = 0; round < 50; ++round) {
    ASSERT_TRUE(set.reset(BlockIndex(round, 0, 0), 10));
    std::atomic<int> firsts{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t) {
      threads.emplace_back([&] {
        for (int x = round - 10; x <= round + 10; ++x) firsts += set.insert(set.bitOf(x, 3, -2));
      });
    }
    for (std::thread& thread : threads) thread.join();
    EXPECT_EQ(firsts.load(), 21);
  }
}

}  // namespace
}  // namespace cblox
