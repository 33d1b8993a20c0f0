#include "core/integrator/rectangle_max_table.h"

#include <algorithm>
#include <random>
#include <stdexcept>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

// Every rectangle of random grids, against a brute-force maximum: grids narrower and wider
// than the top level's squares, one level (single cells only) and several.
TEST(RectangleMaxTable, EveryRectangleGivesItsMaximum) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> value(-1.0f, 3.0f);
  for (const auto& [width, height, levels] :
       {std::tuple{1, 1, 1}, std::tuple{7, 5, 1}, std::tuple{13, 9, 3}, std::tuple{20, 6, 4},
        std::tuple{5, 17, 2}}) {
    std::vector<float> grid(static_cast<size_t>(width * height));
    for (float& v : grid) v = value(rng);
    RectangleMaxTable table;
    std::copy(grid.begin(), grid.end(), table.resetGrid(width, height, levels));
    table.buildLevels();
    ASSERT_EQ(table.width(), width);
    ASSERT_EQ(table.height(), height);
    for (int y0 = 0; y0 < height; ++y0) {
      for (int y1 = y0; y1 < height; ++y1) {
        for (int x0 = 0; x0 < width; ++x0) {
          for (int x1 = x0; x1 < width; ++x1) {
            float expected = grid[static_cast<size_t>(y0 * width + x0)];
            for (int y = y0; y <= y1; ++y) {
              for (int x = x0; x <= x1; ++x) {
                expected = std::max(expected, grid[static_cast<size_t>(y * width + x)]);
              }
            }
            ASSERT_EQ(table.max(x0, x1, y0, y1), expected)
                << width << "x" << height << " levels " << levels << ": [" << x0 << ", " << x1
                << "] x [" << y0 << ", " << y1 << "]";
          }
        }
      }
    }
  }
}

// A single largest value is found from every rectangle that holds it and from none other.
TEST(RectangleMaxTable, APeakIsSeenExactlyByTheRectanglesHoldingIt) {
  constexpr int kWidth = 16, kHeight = 12;
  std::vector<float> grid(kWidth * kHeight, 0.0f);
  grid[5 * kWidth + 9] = 2.5f;
  RectangleMaxTable table;
  std::copy(grid.begin(), grid.end(), table.resetGrid(kWidth, kHeight, 4));
  table.buildLevels();
  for (int y0 = 0; y0 < kHeight; ++y0) {
    for (int y1 = y0; y1 < kHeight; ++y1) {
      for (int x0 = 0; x0 < kWidth; ++x0) {
        for (int x1 = x0; x1 < kWidth; ++x1) {
          const bool holds = x0 <= 9 && 9 <= x1 && y0 <= 5 && 5 <= y1;
          ASSERT_EQ(table.max(x0, x1, y0, y1), holds ? 2.5f : 0.0f);
        }
      }
    }
  }
}

TEST(RectangleMaxTable, RejectsAnEmptyGridOrNoLevel) {
  RectangleMaxTable table;
  EXPECT_THROW(table.resetGrid(0, 1, 1), std::invalid_argument);
  EXPECT_THROW(table.resetGrid(1, 0, 1), std::invalid_argument);
  EXPECT_THROW(table.resetGrid(1, 1, 0), std::invalid_argument);
}

}  // namespace
}  // namespace cblox
