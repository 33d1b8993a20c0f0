#include "core/features/quadtree_distribution.h"

#include <algorithm>
#include <set>

#include <gtest/gtest.h>

namespace cblox {
namespace {

// Corners on every pixel of [0, w) x [0, h), response = 1 + x + w * y (all distinct).
std::vector<LevelCorner> fullGrid(int w, int h) {
  std::vector<LevelCorner> corners;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) corners.push_back({x, y, static_cast<float>(1 + x + w * y)});
  }
  return corners;
}

TEST(QuadtreeDistributionTest, FourNodesKeepTheStrongestCornerOfEachQuadrant) {
  const std::vector<LevelCorner> corners = fullGrid(64, 64);
  const std::vector<int> kept = distributeQuadtree(corners, 0, 64, 0, 64, 4);
  ASSERT_EQ(kept.size(), 4u);
  std::set<std::pair<int, int>> at;
  for (const int i : kept)
    at.insert({corners[static_cast<size_t>(i)].x, corners[static_cast<size_t>(i)].y});
  // The strongest corner of a quadrant is its bottom-right pixel.
  EXPECT_EQ(at, (std::set<std::pair<int, int>>{{31, 31}, {63, 31}, {31, 63}, {63, 63}}));
}

TEST(QuadtreeDistributionTest, EightNodesTileAWideAreaEvenly) {
  // 128 x 64: two initial 64 x 64 nodes side by side, each split once: one node per 32 x 32
  // cell.
  const std::vector<LevelCorner> corners = fullGrid(128, 64);
  const std::vector<int> kept = distributeQuadtree(corners, 0, 128, 0, 64, 8);
  ASSERT_EQ(kept.size(), 8u);
  std::set<std::pair<int, int>> cells;
  for (const int i : kept) {
    const LevelCorner& c = corners[static_cast<size_t>(i)];
    EXPECT_EQ(c.x % 32, 31);  // strongest of its 32 x 32 cell
    EXPECT_EQ(c.y % 32, 31);
    cells.insert({c.x / 32, c.y / 32});
  }
  EXPECT_EQ(cells.size(), 8u);  // one per cell
}

TEST(QuadtreeDistributionTest, IsolatedCornersSurviveADenseCluster) {
  // 900 strong corners packed in a 30 x 30 block in one corner of a 400 x 400 area, plus 6
  // isolated weak corners far apart: spreading keeps every isolated one. (ORB-SLAM2 would stop
  // at 7 nodes here: the pass that splits only the cluster's node into one non-empty quadrant
  // leaves the node count unchanged.)
  std::vector<LevelCorner> corners;
  for (int y = 0; y < 30; ++y) {
    for (int x = 0; x < 30; ++x) corners.push_back({x, y, 100.0f + static_cast<float>(x + y)});
  }
  const std::vector<LevelCorner> isolated = {{350, 20, 1.0f},  {200, 200, 1.0f}, {20, 350, 1.0f},
                                             {390, 390, 1.0f}, {300, 120, 1.0f}, {100, 300, 1.0f}};
  corners.insert(corners.end(), isolated.begin(), isolated.end());
  const std::vector<int> kept = distributeQuadtree(corners, 0, 400, 0, 400, 20);
  ASSERT_EQ(kept.size(), 20u);
  for (size_t k = 0; k < isolated.size(); ++k) {
    EXPECT_NE(std::find(kept.begin(), kept.end(), static_cast<int>(900 + k)), kept.end()) << k;
  }
  // The response-ordered alternative (keep the 20 strongest) would have kept none of them.
}

TEST(QuadtreeDistributionTest, NeverMoreThanWantedAndAllWhenFewer) {
  const std::vector<LevelCorner> corners = fullGrid(50, 40);
  for (const int wanted : {1, 2, 3, 5, 7, 13, 100, 333}) {
    const std::vector<int> kept = distributeQuadtree(corners, 0, 50, 0, 40, wanted);
    EXPECT_EQ(kept.size(), static_cast<size_t>(wanted)) << wanted;
    EXPECT_EQ(std::set<int>(kept.begin(), kept.end()).size(), kept.size()) << wanted;
  }
  const std::vector<LevelCorner> few = {{3, 4, 1.0f}, {10, 30, 2.0f}, {45, 2, 3.0f}};
  EXPECT_EQ(distributeQuadtree(few, 0, 50, 0, 40, 10).size(), 3u);
  EXPECT_TRUE(distributeQuadtree(few, 0, 50, 0, 40, 0).empty());
  EXPECT_TRUE(distributeQuadtree({}, 0, 50, 0, 40, 10).empty());
}

TEST(QuadtreeDistributionTest, IgnoresCornersOutsideTheAreaAndSharesAPixel) {
  const std::vector<LevelCorner> corners = {{-1, 5, 9.0f}, {5, 40, 9.0f}, {50, 5, 9.0f},
                                            {7, 7, 1.0f},  {7, 7, 2.0f},  {30, 30, 1.0f}};
  const std::vector<int> kept = distributeQuadtree(corners, 0, 50, 0, 40, 10);
  // The three outside corners are ignored; the two at (7, 7) share a node (the stronger wins).
  EXPECT_EQ(std::set<int>(kept.begin(), kept.end()), (std::set<int>{4, 5}));
}

}  // namespace
}  // namespace cblox
