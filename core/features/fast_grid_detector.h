#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "core/features/fast_detector.h"

namespace cblox {

/// A FAST corner of one pyramid level: integer pixel (x, y) of that level and its FAST score.
struct LevelCorner {
  int x = 0;
  int y = 0;
  float response = 0.0f;
};

/// Where and how ORB-SLAM2 looks for FAST corners on one pyramid level.
struct FastGridConfig {
  /// Corners lie at least this many pixels from every border of the level (ORB-SLAM2's
  /// EDGE_THRESHOLD = 19: room for the orientation patch (15) and rotated BRIEF (< 19)).
  int edge_threshold = 19;
  /// Side of the square detection cells, pixels at the level (ORB-SLAM2: 30).
  int cell_size = 30;
  /// FAST threshold (grey levels) in every cell; cells where no corner passes it take the
  /// corners of min_threshold instead.
  int initial_threshold = 20;
  int min_threshold = 7;
};

/// ORB-SLAM2's cell-adaptive FAST (ORBextractor::ComputeKeyPointsOctTree, detection part):
/// the detection area [e, W - e) x [e, H - e) (e = edge_threshold) is cut into
/// floor((W - 2e + 6) / cell_size) x floor((H - 2e + 6) / cell_size) cells of equal size (at
/// least one); a cell keeps its FAST corners (9-16, non-maximum suppression) of score >=
/// initial_threshold, or, when it has none, its corners of score >= min_threshold.
///
/// Implementation: the result is that of one FAST pass (FastDetector, identical to cv::FAST) at
/// min_threshold over the whole detection area followed by a per-cell score filter. This gives
/// the same corners and scores as ORB-SLAM2's per-cell cv::FAST calls at the two thresholds (a
/// FAST score is the largest threshold at which the point is still a corner, so "corner at t"
/// == "score >= t", and a corner of score >= t can only be suppressed by a neighbour of higher
/// score, itself a corner at t), except that non-maximum suppression also works across cell
/// borders, so the duplicate corners ORB-SLAM2 finds in the 6-pixel cell overlaps do not occur.
/// It is computed as one pass at initial_threshold over the whole area (where FAST's quick test
/// rejects most pixels) and a pass at min_threshold over the cells without a strong corner only
/// (each with a 4-pixel ring, so that suppression across their borders is the whole pass's).
///
/// Returns corners ordered by cell (row-major) and, within a cell, by row then column. A level
/// smaller than 2e + 1 in either direction gives no corners.
/// Thread-safety: not thread-safe (reuses buffers); one detector per thread.
class FastGridDetector {
 public:
  std::vector<LevelCorner> detect(const cv::Mat& level, const FastGridConfig& params);

 private:
  FastDetector fast_;
  std::vector<FastCorner> fast_corners_, weak_corners_;
  std::vector<int> start_, fill_, order_;
  std::vector<char> strong_;
};

}  // namespace cblox
