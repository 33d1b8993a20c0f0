#pragma once

#include <cstddef>
#include <vector>

#include <opencv2/core.hpp>

namespace cblox {

/// How well a pair is rectified: the vertical offsets |v_left - v_right| (pixels) of the same
/// scene points in the two images, which rectification makes 0. Plain value type.
struct RowErrorStats {
  size_t samples = 0;
  double median_px = 0.0;
  double p90_px = 0.0;
  double max_px = 0.0;
};

/// Median, 90th percentile and maximum of `offsets` (all 0 when empty). Thread-safe (pure).
RowErrorStats summarizeRowErrors(std::vector<double> offsets);

/// Finds the inner corners of a chessboard with `pattern` (columns x rows of inner corners) in
/// both 8-bit grey images (cv::findChessboardCorners, refined with cv::cornerSubPix to
/// 0.01 px) and appends |v_left - v_right| of each corner to *offsets. Returns false (nothing
/// appended) when the board is not found in both. Thread-safe.
bool chessboardRowOffsets(const cv::Mat& left, const cv::Mat& right, cv::Size pattern,
                          std::vector<double>* offsets);

/// For scenes without a board: finds up to 400 corners of `left` (cv::goodFeaturesToTrack) again
/// in `right` by normalised cross-correlation of a 15x15 patch over disparities 0..120 px and
/// vertical offsets within +-max_row_offset px, and appends |v_left - v_right| (sub-pixel by
/// a parabola through the correlation peak) of each confident match (score >= 0.95, peak not
/// on the search band's edge) to *offsets. Returns the number appended. Thread-safe.
size_t featureRowOffsets(const cv::Mat& left, const cv::Mat& right, int max_row_offset,
                         std::vector<double>* offsets);

}  // namespace cblox
