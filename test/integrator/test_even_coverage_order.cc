#include "core/integrator/even_coverage_order.h"

#include <algorithm>

#include <gtest/gtest.h>

namespace cblox {
namespace {

TEST(EvenCoverageOrder, IsAPermutation) {
  for (uint32_t n : {0u, 1u, 2u, 3u, 7u, 8u, 1000u, 307200u}) {
    std::vector<uint32_t> order = evenCoverageOrder(n);
    ASSERT_EQ(order.size(), n);
    std::sort(order.begin(), order.end());
    for (uint32_t i = 0; i < n; ++i) ASSERT_EQ(order[i], i);
  }
}

TEST(EvenCoverageOrder, KnownSmallOrder) {
  EXPECT_EQ(evenCoverageOrder(8), (std::vector<uint32_t>{0, 4, 2, 6, 1, 5, 3, 7}));
  EXPECT_EQ(evenCoverageOrder(5), (std::vector<uint32_t>{0, 4, 2, 1, 3}));
}

TEST(EvenCoverageOrder, EveryPrefixCoversTheImageRows) {
  // A 640x480 row-major image: the first 1/16 of the order touches every 16-row band.
  const uint32_t width = 640, height = 480;
  const std::vector<uint32_t> order = evenCoverageOrder(width * height);
  std::vector<int> band_hits(height / 16, 0);
  std::vector<int> column_band_hits(width / 16, 0);
  for (size_t i = 0; i < order.size() / 16; ++i) {
    ++band_hits[order[i] / width / 16];
    ++column_band_hits[order[i] % width / 16];
  }
  for (int hits : band_hits) EXPECT_GT(hits, 0);
  for (int hits : column_band_hits) EXPECT_GT(hits, 0);
}

}  // namespace
}  // namespace cblox
