#include "core/integrator/grid_ray_traversal.h"

#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

std::vector<GridIndex> walk(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  std::vector<GridIndex> cells;
  for (GridRayTraversal t(a, b);;) {
    cells.push_back(t.cell());
    if (!t.advance()) break;
  }
  return cells;
}

TEST(GridRayTraversal, AxisAlignedRayVisitsEachCellOnce) {
  const auto cells = walk({0.5f, 0.5f, 0.5f}, {4.5f, 0.5f, 0.5f});
  ASSERT_EQ(cells.size(), 5u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(cells[i], GridIndex(i, 0, 0));
}

TEST(GridRayTraversal, NegativeDirectionAndNegativeCells) {
  const auto cells = walk({0.5f, -0.5f, 2.25f}, {0.5f, -0.5f, -1.75f});
  ASSERT_EQ(cells.size(), 5u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(cells[i], GridIndex(0, -1, 2 - i));
}

TEST(GridRayTraversal, SameCell) {
  const auto cells = walk({0.1f, 0.2f, 0.3f}, {0.9f, 0.8f, 0.7f});
  ASSERT_EQ(cells.size(), 1u);
  EXPECT_EQ(cells[0], GridIndex(0, 0, 0));
}

TEST(GridRayTraversal, DiagonalRayIsSixConnectedAndEndsAtTheEndCell) {
  const Eigen::Vector3f a(0.3f, -2.7f, 5.1f), b(7.9f, 3.2f, -4.4f);
  const auto cells = walk(a, b);
  EXPECT_EQ(cells.front(), GridIndex(0, -3, 5));
  EXPECT_EQ(cells.back(), GridIndex(7, 3, -5));
  EXPECT_EQ(cells.size(), 1u + 7u + 6u + 10u);
  for (size_t i = 1; i < cells.size(); ++i) {
    EXPECT_EQ((cells[i] - cells[i - 1]).cwiseAbs().sum(), 1) << i;
  }
  // Every visited cell is really crossed by the segment (within rounding).
  for (const GridIndex& cell : cells) {
    const Eigen::Vector3f lo = cell.cast<float>(), hi = lo + Eigen::Vector3f::Ones();
    // Slab test of the segment against the cell.
    float t0 = 0.0f, t1 = 1.0f;
    for (int axis = 0; axis < 3; ++axis) {
      const float d = b[axis] - a[axis];
      float ta = (lo[axis] - a[axis]) / d, tb = (hi[axis] - a[axis]) / d;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    EXPECT_LE(t0, t1 + 1e-5f) << cell.transpose();
  }
}

}  // namespace
}  // namespace cblox
