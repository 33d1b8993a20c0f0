#include "core/tracking/feature_grid.h"

#include <algorithm>
#include <cmath>

namespace cblox {

FeatureGrid::FeatureGrid(const std::vector<Keypoint>& keypoints, int width, int height, int cols,
                         int rows)
    : cols_(std::max(cols, 1)),
      rows_(std::max(rows, 1)),
      cell_w_(static_cast<float>(std::max(width, 1)) / static_cast<float>(std::max(cols, 1))),
      cell_h_(static_cast<float>(std::max(height, 1)) / static_cast<float>(std::max(rows, 1))),
      cells_(static_cast<size_t>(cols_) * static_cast<size_t>(rows_)) {
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const int cx = static_cast<int>(std::floor(keypoints[i].u / cell_w_));
    const int cy = static_cast<int>(std::floor(keypoints[i].v / cell_h_));
    if (cx < 0 || cy < 0 || cx >= cols_ || cy >= rows_) continue;
    cells_[static_cast<size_t>(cy * cols_ + cx)].push_back(static_cast<uint32_t>(i));
  }
}

std::vector<uint32_t> FeatureGrid::featuresInArea(const std::vector<Keypoint>& keypoints, float u,
                                                  float v, float radius, int min_octave,
                                                  int max_octave) const {
  std::vector<uint32_t> result;
  if (cells_.empty() || !(radius >= 0.0f)) return result;
  const int x0 = std::max(0, static_cast<int>(std::floor((u - radius) / cell_w_)));
  const int x1 = std::min(cols_ - 1, static_cast<int>(std::floor((u + radius) / cell_w_)));
  const int y0 = std::max(0, static_cast<int>(std::floor((v - radius) / cell_h_)));
  const int y1 = std::min(rows_ - 1, static_cast<int>(std::floor((v + radius) / cell_h_)));
  for (int cy = y0; cy <= y1; ++cy) {
    for (int cx = x0; cx <= x1; ++cx) {
      for (const uint32_t i : cells_[static_cast<size_t>(cy * cols_ + cx)]) {
        const Keypoint& k = keypoints[i];
        if (k.octave < min_octave || (max_octave >= 0 && k.octave > max_octave)) continue;
        if (std::abs(k.u - u) <= radius && std::abs(k.v - v) <= radius) result.push_back(i);
      }
    }
  }
  std::sort(result.begin(), result.end());
  return result;
}

}  // namespace cblox
