#include <gtest/gtest.h>

#include <vector>

#include "core/tracking/feature_matcher.h"

namespace cblox {
namespace {

TEST(RotationConsistencyTest, NoMatchesKeepNothing) {
  EXPECT_TRUE(consistentRotations({}).empty());
}

// Correct matches spread by up to 25 degrees around no rotation (as on smooth textures)
// all stay; changes 40 degrees or more away from it are dropped.
TEST(RotationConsistencyTest, KeepsTheSpreadAroundTheDominantChangeAndDropsTheRest) {
  std::vector<float> rotations;
  for (int i = 0; i < 50; ++i) rotations.push_back(static_cast<float>(i % 11) - 5.0f);  // -5..5
  rotations.push_back(25.0f);   // 50: kept (within 30 of ~0)
  rotations.push_back(-24.0f);  // 51: kept
  rotations.push_back(40.0f);   // 52: dropped
  rotations.push_back(180.0f);  // 53: dropped
  rotations.push_back(-60.0f);  // 54: dropped
  rotations.push_back(335.0f);  // 55: -25, kept
  const std::vector<size_t> keep = consistentRotations(rotations);
  std::vector<size_t> expected;
  for (size_t i = 0; i < 52; ++i) expected.push_back(i);
  expected.push_back(55);
  EXPECT_EQ(keep, expected);
}

// A camera roll of 90 degrees between the images shifts every change by 90: the window
// follows it, across the 0/360 wrap too.
TEST(RotationConsistencyTest, FollowsARotatedCluster) {
  for (const float shift : {90.0f, 358.0f, -178.0f}) {
    std::vector<float> rotations;
    for (int i = 0; i < 30; ++i) rotations.push_back(shift + static_cast<float>(i % 7) - 3.0f);
    rotations.push_back(shift + 28.0f);   // 30: kept
    rotations.push_back(shift - 33.0f);   // 31: dropped
    rotations.push_back(shift + 180.0f);  // 32: dropped
    const std::vector<size_t> keep = consistentRotations(rotations);
    ASSERT_EQ(keep.size(), 31u) << "shift " << shift;
    EXPECT_EQ(keep.back(), 30u) << "shift " << shift;
  }
}

// Two clusters: the larger one wins, the smaller one (outliers that agree by chance) goes.
TEST(RotationConsistencyTest, TheLargerClusterWins) {
  std::vector<float> rotations(20, 10.0f);
  rotations.insert(rotations.end(), 8, 120.0f);
  const std::vector<size_t> keep = consistentRotations(rotations);
  ASSERT_EQ(keep.size(), 20u);
  EXPECT_EQ(keep.front(), 0u);
  EXPECT_EQ(keep.back(), 19u);
}

}  // namespace
}  // namespace cblox
