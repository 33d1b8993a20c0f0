#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace cblox {

/// A FAST corner: integer pixel (x, y) of the image it was detected in, and its score.
struct FastCorner {
  int x = 0;
  int y = 0;
  int score = 0;
};

/// FAST-9 corners (segment test on the 16-pixel Bresenham circle of radius 3: 9 contiguous
/// circle pixels all brighter than centre + threshold or all darker than centre - threshold)
/// with non-maximum suppression over the 8-neighbourhood, bit-identical to
/// cv::FAST(image, keypoints, threshold, true) with TYPE_9_16: the same corners in the same
/// (row-major) order, score = OpenCV's cornerScore (the largest threshold at which the pixel is
/// still a corner), and a corner is kept when its score is greater than that of each of its 8
/// neighbours (non-corners count as 0). Pixels within 3 of the border are never corners.
///
/// The segment test and the score of 32 pixels (AVX2, chosen at run time) or 16 pixels (SSE2)
/// come out of one branch-free computation, so the cost hardly depends on the threshold:
/// on a 752x480 simulator image it is as fast as cv::FAST at threshold 20 and 2.5 times faster
/// at threshold 7, where many pixels pass (see cblox-bench-features).
///
/// `image` is CV_8UC1 (any step, e.g. a window of a larger image: only its own pixels are
/// read); thresholds outside [0, 255] are clamped. Throws std::invalid_argument for another
/// image type. Not thread-safe (reuses internal buffers): one detector per thread.
class FastDetector {
 public:
  void detect(const cv::Mat& image, int threshold, std::vector<FastCorner>* corners);

 private:
  std::vector<uint8_t> scores_;  // per pixel (rows padded): score, 0 = no corner
};

}  // namespace cblox
