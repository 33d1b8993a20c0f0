#include "core/covariance/block_ordering.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include <gtest/gtest.h>

#include "test/covariance/covariance_test_util.h"
#include "test/test_support/enum_names.h"

namespace cblox {
namespace {

using test::loopS;

bool isPermutation(std::vector<int> perm, int n) {
  if (static_cast<int>(perm.size()) != n) return false;
  std::sort(perm.begin(), perm.end());
  std::vector<int> identity(n);
  std::iota(identity.begin(), identity.end(), 0);
  return perm == identity;
}

TEST(BlockOrdering, EveryOrderingIsAPermutationOfTheBlocks) {
  const ReducedCameraMatrix S = loopS(60);
  ASSERT_EQ(S.numBlocks(), 59);  // the first keyframe fixes the gauge
  for (const BlockOrdering o : {BlockOrdering::kAmd, BlockOrdering::kNestedDissection}) {
    SCOPED_TRACE(blockOrderingName(o));
    const std::vector<int> perm = blockOrdering(S, o);
    EXPECT_TRUE(isPermutation(perm, S.numBlocks()));
    EXPECT_EQ(blockOrdering(S, o), perm);  // deterministic (METIS is seeded)
  }
  EXPECT_TRUE(blockNestedDissectionOrdering(ReducedCameraMatrix{}).empty());
  EXPECT_NE(blockNestedDissectionOrdering(S), blockAmdOrdering(S));
  EXPECT_THROW(blockOrdering(S, static_cast<BlockOrdering>(5)), std::invalid_argument);
}

TEST(BlockOrdering, NamesRoundTrip) {
  test::expectNamesRoundTrip({BlockOrdering::kAmd, BlockOrdering::kNestedDissection},
                             blockOrderingName, parseBlockOrdering, "metis");
}

}  // namespace
}  // namespace cblox
