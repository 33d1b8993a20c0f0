#include "core/integrator/rectangle_max_table.h"

#include <algorithm>
#include <cstddef>
#include <stdexcept>

namespace cblox {

float* RectangleMaxTable::resetGrid(int width, int height, int levels) {
  if (width < 1 || height < 1 || levels < 1) {
    throw std::invalid_argument("RectangleMaxTable: empty grid or no level");
  }
  width_ = width;
  height_ = height;
  levels_ = levels;
  cells_ = static_cast<size_t>(width) * static_cast<size_t>(height);
  data_.resize(cells_ * static_cast<size_t>(levels));
  return data_.data();
}

void RectangleMaxTable::buildLevels() {
  const int width = width_, height = height_;
  // Level k from level k - 1: the four squares of half the side that make up each square.
  // Only the cells whose square lies inside the grid are filled (and ever read).
  for (int level = 1; level < levels_; ++level) {
    const int half = 1 << (level - 1), side = 1 << level;
    const float* below = data_.data() + static_cast<size_t>(level - 1) * cells_;
    float* out = data_.data() + static_cast<size_t>(level) * cells_;
    for (int y = 0; y + side <= height; ++y) {
      const float* a = below + static_cast<size_t>(y) * width;
      const float* b = a + static_cast<size_t>(half) * width;
      float* o = out + static_cast<size_t>(y) * width;
      for (int x = 0; x + side <= width; ++x) {
        o[x] = std::max(std::max(a[x], a[x + half]), std::max(b[x], b[x + half]));
      }
    }
  }
}

}  // namespace cblox
