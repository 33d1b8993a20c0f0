#include "core/features/scale_pyramid.h"

#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace cblox {

std::string ScalePyramid::validate(int num_levels, double scale_factor) {
  if (num_levels < 1 || num_levels > 32) {
    return "num_levels must be in [1, 32], got " + std::to_string(num_levels);
  }
  if (!std::isfinite(scale_factor) || scale_factor <= 1.0 || scale_factor > 4.0) {
    return "scale_factor must be in (1, 4], got " + std::to_string(scale_factor);
  }
  return "";
}

ScalePyramid::ScalePyramid(int num_levels, double scale_factor) : scale_factor_(scale_factor) {
  const std::string error = validate(num_levels, scale_factor);
  if (!error.empty()) throw std::invalid_argument("ScalePyramid: " + error);
  const size_t n = static_cast<size_t>(num_levels);
  scale_.assign(n, 1.0f);
  sigma2_.assign(n, 1.0f);
  for (size_t i = 1; i < n; ++i) {
    scale_[i] = scale_[i - 1] * static_cast<float>(scale_factor);
    sigma2_[i] = scale_[i] * scale_[i];
  }
  inv_scale_.resize(n);
  inv_sigma2_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    inv_scale_[i] = 1.0f / scale_[i];
    inv_sigma2_[i] = 1.0f / sigma2_[i];
  }
}

cv::Size ScalePyramid::levelSize(cv::Size level0, int level) const {
  const float s = invScale(level);
  return {cvRound(static_cast<float>(level0.width) * s),
          cvRound(static_cast<float>(level0.height) * s)};
}

std::vector<cv::Mat> ScalePyramid::build(const cv::Mat& image) const {
  if (image.empty()) throw std::invalid_argument("ScalePyramid::build: empty image");
  if (image.type() != CV_8UC1) {
    throw std::invalid_argument("ScalePyramid::build: image must be CV_8UC1");
  }
  std::vector<cv::Mat> levels(static_cast<size_t>(numLevels()));
  levels[0] = image.clone();
  for (int i = 1; i < numLevels(); ++i) {
    const cv::Size size = levelSize(image.size(), i);
    const cv::Mat& previous = levels[static_cast<size_t>(i - 1)];
    if (size.width <= 0 || size.height <= 0 || previous.empty()) continue;
    cv::resize(previous, levels[static_cast<size_t>(i)], size, 0, 0, cv::INTER_LINEAR);
  }
  return levels;
}

}  // namespace cblox
