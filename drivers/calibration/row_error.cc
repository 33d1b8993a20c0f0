#include "drivers/calibration/row_error.h"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/common/quantile.h"

namespace cblox {

RowErrorStats summarizeRowErrors(std::vector<double> offsets) {
  RowErrorStats stats;
  stats.samples = offsets.size();
  if (offsets.empty()) return stats;
  stats.median_px = quantile(&offsets, 0.5);
  stats.p90_px = quantile(&offsets, 0.9);
  stats.max_px = *std::max_element(offsets.begin(), offsets.end());
  return stats;
}

bool chessboardRowOffsets(const cv::Mat& left, const cv::Mat& right, cv::Size pattern,
                          std::vector<double>* offsets) {
  std::vector<cv::Point2f> corners[2];
  const cv::Mat* images[2] = {&left, &right};
  for (int i = 0; i < 2; ++i) {
    if (!cv::findChessboardCorners(*images[i], pattern, corners[i],
                                   cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
      return false;
    }
    cv::cornerSubPix(*images[i], corners[i], cv::Size(11, 11), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 50, 0.01));
  }
  if (corners[0].size() != corners[1].size()) return false;
  for (size_t k = 0; k < corners[0].size(); ++k) {
    offsets->push_back(std::abs(static_cast<double>(corners[0][k].y) - corners[1][k].y));
  }
  return true;
}

size_t featureRowOffsets(const cv::Mat& left, const cv::Mat& right, int max_row_offset,
                         std::vector<double>* offsets) {
  constexpr int kHalf = 7;
  constexpr int kMaxDisparity = 120;
  constexpr double kMinScore = 0.95;
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(left, corners, 400, 0.01, 10);
  size_t appended = 0;
  for (const cv::Point2f& corner : corners) {
    const int x = static_cast<int>(std::lround(corner.x));
    const int y = static_cast<int>(std::lround(corner.y));
    const int x0 = x - kMaxDisparity - kHalf;
    const int y0 = y - max_row_offset - kHalf;
    const int x1 = x + 2 + kHalf;
    const int y1 = y + max_row_offset + kHalf;
    if (x - kHalf < 0 || x0 < 0 || y0 < 0 || x1 >= right.cols || y1 >= right.rows) continue;
    const cv::Mat patch = left(cv::Rect(x - kHalf, y - kHalf, 2 * kHalf + 1, 2 * kHalf + 1));
    const cv::Mat band = right(cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1));
    cv::Mat score;
    cv::matchTemplate(band, patch, score, cv::TM_CCOEFF_NORMED);
    double best = 0.0;
    cv::Point peak;
    cv::minMaxLoc(score, nullptr, &best, nullptr, &peak);
    if (best < kMinScore || peak.y == 0 || peak.y == score.rows - 1) continue;
    const float above = score.at<float>(peak.y - 1, peak.x);
    const float at = score.at<float>(peak.y, peak.x);
    const float below = score.at<float>(peak.y + 1, peak.x);
    const double curvature = above - 2.0 * at + below;
    const double sub = curvature < 0 ? 0.5 * (above - below) / curvature : 0.0;
    const double v_right = y0 + peak.y + kHalf + sub;
    offsets->push_back(std::abs(v_right - y));
    ++appended;
  }
  return appended;
}

}  // namespace cblox
