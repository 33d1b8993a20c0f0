#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace cblox {

/// The maximum over any rectangle of a grid of floats in a few lookups: a sparse table of
/// squares, where level k holds per cell the maximum of the 2^k x 2^k square whose first cell
/// it is. A rectangle is covered by squares of the largest level that fits its shorter side
/// (overlapping at its far edges, which a maximum does not mind): 4 lookups for a square,
/// about 2 * long / short for a long one, more when it is wider than the top level.
///
/// Thread safety: max() is const and may run concurrently; resetGrid() and buildLevels() must
/// not. Different cells of the grid may be filled concurrently.
class RectangleMaxTable {
 public:
  /// Sizes the table for a width x height grid (row-major) with squares of up to
  /// 2^(levels - 1) cells per side, and returns the grid, to be filled before buildLevels().
  /// Throws std::invalid_argument for an empty grid or levels < 1.
  float* resetGrid(int width, int height, int levels);
  /// The levels above the grid, from its values.
  void buildLevels();

  /// The maximum of columns [x0, x1] and rows [y0, y1], inclusive; 0 <= x0 <= x1 < width and
  /// 0 <= y0 <= y1 < height.
  float max(int x0, int x1, int y0, int y1) const {
    const int shorter = std::min(x1 - x0, y1 - y0) + 1;
    int level = 31 - __builtin_clz(static_cast<unsigned>(shorter));
    if (level >= levels_) level = levels_ - 1;
    const int side = 1 << level;
    const float* table = data_.data() + static_cast<size_t>(level) * cells_;
    const int x_last = x1 - side + 1, y_last = y1 - side + 1;
    float m = table[static_cast<size_t>(y0) * width_ + x0];
    for (int y = y0;; y += side) {
      const int row = y < y_last ? y : y_last;
      const float* line = table + static_cast<size_t>(row) * width_;
      for (int x = x0;; x += side) {
        const int column = x < x_last ? x : x_last;
        m = line[column] > m ? line[column] : m;
        if (column == x_last) break;
      }
      if (row == y_last) break;
    }
    return m;
  }

  /// The grid (level 0) of the last resetGrid().
  float* grid() { return data_.data(); }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int width_ = 0, height_ = 0, levels_ = 0;
  size_t cells_ = 0;
  std::vector<float> data_;  // levels_ grids of width_ x height_
};

}  // namespace cblox
