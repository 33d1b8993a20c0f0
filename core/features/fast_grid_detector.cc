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
  // A cell falls back to the minimum threshold only when it has no corner at the initial one,
  // so the first pass runs at the higher of the two (the initial one when it is higher).
  const bool fallback = params.initial_threshold > params.min_threshold;
  fast_.detect(level(area), fallback ? params.initial_threshold : params.min_threshold,
               &fast_corners_);

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

  // Counting sort of the first pass's corners by cell (row-major order kept within a cell).
  start_.assign(n_cells + 1, 0);
  for (const FastCorner& c : fast_corners_) ++start_[cellOf(c) + 1];
  for (size_t c = 0; c < n_cells; ++c) start_[c + 1] += start_[c];
  order_.resize(fast_corners_.size());
  fill_.assign(start_.begin(), start_.end() - 1);
  for (size_t i = 0; i < fast_corners_.size(); ++i) {
    order_[static_cast<size_t>(fill_[cellOf(fast_corners_[i])]++)] = static_cast<int>(i);
  }
  corners.reserve(fast_corners_.size());
  for (size_t c = 0; c < n_cells; ++c) {
    if (start_[c] == start_[c + 1]) {
      if (fallback)
        appendWeakCell(level, area, c, n_cols, n_rows, cell_w, cell_h, params, &corners);
      continue;
    }
    for (int k = start_[c]; k < start_[c + 1]; ++k) {
      const FastCorner& fc = fast_corners_[static_cast<size_t>(order_[static_cast<size_t>(k)])];
      corners.push_back({fc.x + area.x, fc.y + area.y, static_cast<float>(fc.score)});
    }
  }
  return corners;
}

void FastGridDetector::appendWeakCell(const cv::Mat& level, const cv::Rect& area, size_t cell,
                                      int n_cols, int n_rows, int cell_w, int cell_h,
                                      const FastGridConfig& params,
                                      std::vector<LevelCorner>* corners) {
  // The pixels the cell owns, in area coordinates (corners are scored in [3, size - 3)).
  const int cx = static_cast<int>(cell % static_cast<size_t>(n_cols));
  const int cy = static_cast<int>(cell / static_cast<size_t>(n_cols));
  const int x0 = 3 + cx * cell_w, y0 = 3 + cy * cell_h;
  const int x1 = cx == n_cols - 1 ? area.width - 3 : std::min(area.width - 3, x0 + cell_w);
  const int y1 = cy == n_rows - 1 ? area.height - 3 : std::min(area.height - 3, y0 + cell_h);
  if (x0 >= x1 || y0 >= y1) return;
  // The window adds the 3-pixel ring FAST reads and one more pixel, so that the scores of the
  // owned pixels' 8 neighbours (non-maximum suppression) are those of the whole-area pass.
  constexpr int kGrow = 4;
  const cv::Rect window(std::max(0, x0 - kGrow), std::max(0, y0 - kGrow),
                        std::min(area.width, x1 + kGrow) - std::max(0, x0 - kGrow),
                        std::min(area.height, y1 + kGrow) - std::max(0, y0 - kGrow));
  fast_.detect(level(area)(window), params.min_threshold, &weak_corners_);
  for (const FastCorner& fc : weak_corners_) {
    const int x = fc.x + window.x, y = fc.y + window.y;  // area coordinates
    if (x < x0 || x >= x1 || y < y0 || y >= y1) continue;
    corners->push_back({x + area.x, y + area.y, static_cast<float>(fc.score)});
  }
}

}  // namespace cblox
