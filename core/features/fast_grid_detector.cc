#include "core/features/fast_grid_detector.h"

#include <algorithm>
#include <cmath>

namespace cblox {

std::vector<LevelCorner> FastGridDetector::detect(const cv::Mat& level,
                                                  const FastGridConfig& params) {
  std::vector<LevelCorner> corners;
  const int e = params.edge_threshold;
  if (level.cols < 2 * e + 1 || level.rows < 2 * e + 1) return corners;
  // Corners lie in [e, W - e) x [e, H - e); FAST needs a 3-pixel ring around a candidate, so
  // it runs on the area grown by 3 pixels (ORB-SLAM2's [e - 3, W - e + 3)).
  const cv::Rect area(e - 3, e - 3, level.cols - 2 * e + 6, level.rows - 2 * e + 6);
  fast_.detect(level(area), params.min_threshold, &fast_corners_);
  if (fast_corners_.empty()) return corners;

  // Cells as ORB-SLAM2 lays them out: cell (i, j) owns corners with
  // x in [e + j * cell_w, e + (j + 1) * cell_w) (the last one up to W - e), likewise y.
  const int n_cols = std::max(1, area.width / params.cell_size);
  const int n_rows = std::max(1, area.height / params.cell_size);
  const int cell_w = static_cast<int>(std::ceil(static_cast<float>(area.width) / n_cols));
  const int cell_h = static_cast<int>(std::ceil(static_cast<float>(area.height) / n_rows));
  const size_t n_cells = static_cast<size_t>(n_cols) * static_cast<size_t>(n_rows);
  // Area coordinates: corners start 3 pixels inside the area.
  const auto cellOf = [&](const FastCorner& c) {
    const int cx = std::min(n_cols - 1, (c.x - 3) / cell_w);
    const int cy = std::min(n_rows - 1, (c.y - 3) / cell_h);
    return static_cast<size_t>(cy * n_cols + cx);
  };

  // Counting sort by cell; a cell is "strong" when it has a corner at the initial threshold.
  start_.assign(n_cells + 1, 0);
  strong_.assign(n_cells, 0);
  for (const FastCorner& c : fast_corners_) {
    const size_t cell = cellOf(c);
    ++start_[cell + 1];
    if (c.score >= params.initial_threshold) strong_[cell] = 1;
  }
  for (size_t c = 0; c < n_cells; ++c) start_[c + 1] += start_[c];
  order_.resize(fast_corners_.size());
  fill_.assign(start_.begin(), start_.end() - 1);
  for (size_t i = 0; i < fast_corners_.size(); ++i) {
    order_[static_cast<size_t>(fill_[cellOf(fast_corners_[i])]++)] = static_cast<int>(i);
  }
  corners.reserve(fast_corners_.size());
  for (size_t c = 0; c < n_cells; ++c) {
    for (int k = start_[c]; k < start_[c + 1]; ++k) {
      const FastCorner& fc = fast_corners_[static_cast<size_t>(order_[static_cast<size_t>(k)])];
      if (strong_[c] && fc.score < params.initial_threshold) continue;
      corners.push_back({fc.x + area.x, fc.y + area.y, static_cast<float>(fc.score)});
    }
  }
  return corners;
}

}  // namespace cblox
