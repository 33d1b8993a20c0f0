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

  // 1. The strong corners: one pass over the whole area at the initial threshold (FAST's
  // quick test rejects most pixels there). A corner of score >= t is suppressed only by a
  // neighbour of higher score, itself a corner at t, so these are exactly the corners of
  // score >= t of a pass at the minimum threshold.
  const int strong_threshold = std::max(params.initial_threshold, params.min_threshold);
  fast_.detect(level(area), strong_threshold, &fast_corners_);
  strong_.assign(n_cells, 0);
  for (const FastCorner& c : fast_corners_) strong_[cellOf(c)] = 1;

  // 2. The weak cells (no strong corner) at the minimum threshold: each run of weak cells of
  // a cell row in one window, grown by 4 pixels (clipped to the area) so that the scores of
  // the 8 neighbours of each of its pixels, which non-maximum suppression compares, are those
  // of a whole-area pass.
  if (params.min_threshold < params.initial_threshold) {
    constexpr int kRing = 4;
    for (int i = 0; i < n_rows; ++i) {
      const int y0 = 3 + i * cell_h;
      const int y1 = i == n_rows - 1 ? area.height - 3 : std::min(area.height - 3, y0 + cell_h);
      for (int j = 0; j < n_cols;) {
        if (strong_[static_cast<size_t>(i * n_cols + j)]) {
          ++j;
          continue;
        }
        int j_end = j + 1;
        while (j_end < n_cols && !strong_[static_cast<size_t>(i * n_cols + j_end)]) ++j_end;
        const int x0 = 3 + j * cell_w;
        const int x1 =
            j_end == n_cols ? area.width - 3 : std::min(area.width - 3, 3 + j_end * cell_w);
        j = j_end;
        if (x0 >= x1 || y0 >= y1) continue;
        const cv::Rect window =
            cv::Rect(x0 - kRing, y0 - kRing, x1 - x0 + 2 * kRing, y1 - y0 + 2 * kRing) &
            cv::Rect(0, 0, area.width, area.height);
        fast_.detect(level(area)(window), params.min_threshold, &weak_corners_);
        for (FastCorner c : weak_corners_) {
          c.x += window.x;
          c.y += window.y;
          if (c.x >= x0 && c.x < x1 && c.y >= y0 && c.y < y1) fast_corners_.push_back(c);
        }
      }
    }
  }
  if (fast_corners_.empty()) return corners;

  // Counting sort by cell, stable: a cell's corners stay in row-major order.
  start_.assign(n_cells + 1, 0);
  for (const FastCorner& c : fast_corners_) ++start_[cellOf(c) + 1];
  for (size_t c = 0; c < n_cells; ++c) start_[c + 1] += start_[c];
  order_.resize(fast_corners_.size());
  fill_.assign(start_.begin(), start_.end() - 1);
  for (size_t i = 0; i < fast_corners_.size(); ++i) {
    order_[static_cast<size_t>(fill_[cellOf(fast_corners_[i])]++)] = static_cast<int>(i);
  }
  corners.reserve(fast_corners_.size());
  for (const int k : order_) {
    const FastCorner& fc = fast_corners_[static_cast<size_t>(k)];
    corners.push_back({fc.x + area.x, fc.y + area.y, static_cast<float>(fc.score)});
  }
  return corners;
}

}  // namespace cblox
