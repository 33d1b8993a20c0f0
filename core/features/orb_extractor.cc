#include "core/features/orb_extractor.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/features/fast_grid_detector.h"
#include "core/features/quadtree_distribution.h"
#include "core/geometry/opencv_view.h"

namespace cblox {

std::string OrbExtractorConfig::validate() const {
  if (num_features < 1 || num_features > 1000000) {
    return "num_features must be in [1, 1000000], got " + std::to_string(num_features);
  }
  const std::string pyramid = ScalePyramid::validate(num_levels, scale_factor);
  if (!pyramid.empty()) return pyramid;
  if (initial_fast_threshold < 1 || initial_fast_threshold > 254) {
    return "initial_fast_threshold must be in [1, 254], got " +
           std::to_string(initial_fast_threshold);
  }
  if (min_fast_threshold < 1 || min_fast_threshold > initial_fast_threshold) {
    return "min_fast_threshold must be in [1, initial_fast_threshold = " +
           std::to_string(initial_fast_threshold) + "], got " + std::to_string(min_fast_threshold);
  }
  return "";
}

namespace {

const OrbExtractorConfig& checked(const OrbExtractorConfig& config) {
  const std::string error = config.validate();
  if (!error.empty()) throw std::invalid_argument("OrbExtractorConfig: " + error);
  return config;
}

// ORB-SLAM2's share of features per level (float arithmetic as ORB-SLAM2).
std::vector<int> levelShares(const OrbExtractorConfig& config) {
  const int levels = config.num_levels;
  std::vector<int> n(static_cast<size_t>(levels), 0);
  const float factor = 1.0f / static_cast<float>(config.scale_factor);
  float desired = static_cast<float>(config.num_features) * (1 - factor) /
                  (1 - static_cast<float>(std::pow(static_cast<double>(factor), levels)));
  int sum = 0;
  for (int level = 0; level < levels - 1; ++level) {
    n[static_cast<size_t>(level)] = cvRound(desired);
    sum += n[static_cast<size_t>(level)];
    desired *= factor;
  }
  n[static_cast<size_t>(levels - 1)] = std::max(config.num_features - sum, 0);
  return n;
}

}  // namespace

OrbExtractor::OrbExtractor(const OrbExtractorConfig& config)
    : config_(checked(config)),
      scales_(config.num_levels, config.scale_factor),
      features_per_level_(levelShares(config)) {}

ExtractedFeatures OrbExtractor::extract(const GrayImage& image) {
  if (image.empty()) throw std::invalid_argument("OrbExtractor::extract: empty image");
  if (image.data.size() != static_cast<size_t>(image.width) * static_cast<size_t>(image.height)) {
    throw std::invalid_argument("OrbExtractor::extract: image data holds " +
                                std::to_string(image.data.size()) + " pixels, not " +
                                std::to_string(image.width) + "x" + std::to_string(image.height));
  }
  return extract(cvView(image));
}

ExtractedFeatures OrbExtractor::extract(const cv::Mat& image) {
  if (image.empty()) throw std::invalid_argument("OrbExtractor::extract: empty image");
  if (image.type() != CV_8UC1) {
    throw std::invalid_argument("OrbExtractor::extract: image must be 8-bit grey (CV_8UC1)");
  }
  constexpr int kMin = OrbExtractorConfig::kMinImageSide;
  if (image.cols < kMin || image.rows < kMin) {
    throw std::invalid_argument(
        "OrbExtractor::extract: image " + std::to_string(image.cols) + "x" +
        std::to_string(image.rows) +
        " is smaller than the border: both sides must be >= " + std::to_string(kMin) + " pixels");
  }
  ExtractedFeatures out;
  out.scales = scales_;
  out.pyramid = scales_.build(image);
  out.keypoints.reserve(static_cast<size_t>(config_.num_features));
  out.descriptors.reserve(static_cast<size_t>(config_.num_features));

  FastGridConfig grid;
  grid.edge_threshold = OrbExtractorConfig::kEdgeThreshold;
  grid.cell_size = OrbExtractorConfig::kCellSize;
  grid.initial_threshold = config_.initial_fast_threshold;
  grid.min_threshold = config_.min_fast_threshold;
  // The quadtree spans ORB-SLAM2's area [e - 3, size - e + 3).
  constexpr int kMargin = OrbExtractorConfig::kEdgeThreshold - 3;

  for (int level = 0; level < scales_.numLevels(); ++level) {
    const cv::Mat& img = out.pyramid[static_cast<size_t>(level)];
    const int wanted = features_per_level_[static_cast<size_t>(level)];
    if (img.empty() || wanted <= 0) continue;
    const std::vector<LevelCorner> corners = fast_grid_.detect(img, grid);
    if (corners.empty()) continue;
    const std::vector<int> kept = distributeQuadtree(corners, kMargin, img.cols - kMargin, kMargin,
                                                     img.rows - kMargin, wanted);
    blur_.apply(img, &blurred_);
    const float scale = scales_.scale(level);
    for (const int i : kept) {
      const LevelCorner& c = corners[static_cast<size_t>(i)];
      Keypoint kp;
      kp.angle_deg = orientation_.angleDeg(img, c.x, c.y);
      kp.u = static_cast<float>(c.x) * scale;
      kp.v = static_cast<float>(c.y) * scale;
      kp.response = c.response;
      kp.octave = level;
      out.keypoints.push_back(kp);
      out.descriptors.push_back(
          brief_.compute(blurred_, static_cast<float>(c.x), static_cast<float>(c.y), kp.angle_deg));
    }
  }
  return out;
}

}  // namespace cblox
