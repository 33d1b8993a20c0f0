#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "core/features/brief_blur.h"
#include "core/features/fast_grid_detector.h"
#include "core/features/keypoint.h"
#include "core/features/orb_descriptor.h"
#include "core/features/orb_orientation.h"
#include "core/features/rotated_brief.h"
#include "core/features/scale_pyramid.h"
#include "core/geometry/image.h"

namespace cblox {

/// Settings of the ORB-SLAM2-style feature extractor.
struct OrbExtractorConfig {
  /// Features wanted per image (all levels), >= 1. ORB-SLAM2 uses 1000-2000.
  int num_features = 1200;
  /// Scale between consecutive pyramid levels, in (1, 4].
  double scale_factor = 1.2;
  /// Pyramid levels, in [1, 32].
  int num_levels = 8;
  /// FAST threshold (grey levels) tried first in every detection cell, in [1, 254].
  int initial_fast_threshold = 20;
  /// FAST threshold for cells where the initial one finds no corner, in [1, initial].
  int min_fast_threshold = 7;

  /// Fixed constants of the method (pixels at the keypoint's level):
  /// keypoints lie at least kEdgeThreshold from every border of their level (ORB-SLAM2's
  /// EDGE_THRESHOLD: room for the orientation patch of radius 15 and for rotated BRIEF, whose
  /// samples lie within 19 pixels).
  static constexpr int kEdgeThreshold = 19;
  /// Side of the descriptor patch (rotated BRIEF's 31x31 pattern); the orientation patch is
  /// the inscribed circle of radius kPatchSize / 2 = 15.
  static constexpr int kPatchSize = 31;
  /// Side of the FAST detection cells (ORB-SLAM2: 30).
  static constexpr int kCellSize = 30;
  /// Smallest image side accepted: level 0 needs a detection area of at least one pixel.
  static constexpr int kMinImageSide = 2 * kEdgeThreshold + 1;

  /// Empty when valid, else a message naming the first bad field. Thread-safe.
  std::string validate() const;
};

/// What the extractor delivers for one image. Plain value type; owns all its data (nothing is
/// shared with the extractor, so it stays valid after the next extract()).
struct ExtractedFeatures {
  /// Keypoints in level-0 pixel coordinates, grouped by level (level 0 first).
  std::vector<Keypoint> keypoints;
  /// descriptors[i] belongs to keypoints[i].
  std::vector<OrbDescriptor> descriptors;
  /// The image pyramid the keypoints were detected in: pyramid[l] is level l (CV_8UC1,
  /// continuous, NOT blurred; pyramid[0] is a copy of the input), sized
  /// scales.levelSize(image size, l). Stereo matching refines matches with SAD on it.
  std::vector<cv::Mat> pyramid;
  /// The scale factors of the pyramid levels.
  ScalePyramid scales;
};

/// ORB-SLAM2's ORB extractor (ORBextractor::operator()), on OpenCV:
///  1. pyramid: num_levels levels, level i of size round(level-0 size / scale_factor^i), each
///     resized from the one above (ScalePyramid::build, cv::resize INTER_LINEAR);
///  2. features per level: level 0 gets N (1 - 1/f) / (1 - (1/f)^L) (rounded), each further
///     level 1/f times the previous one, the last level the remainder (featuresPerLevel());
///  3. per level, FAST in cells of 30 px with initial_fast_threshold, min_fast_threshold in
///     cells without corners (FastGridDetector; its FAST is FastDetector, identical to
///     cv::FAST), then ORB-SLAM2's quadtree distribution keeps at most the level's share, the
///     strongest corner per node (distributeQuadtree, which also documents where it departs
///     from ORB-SLAM2: it does not stop early on clustered corners, never exceeds the share);
///  4. orientation by intensity centroid over the radius-15 circular patch of the level image
///     (OrbOrientation);
///  5. descriptor: rotated BRIEF (256 bits, OpenCV's 31x31 pattern) of the level image blurred
///     with a 7x7 Gaussian of sigma 2 (RotatedBrief), bit-identical to OpenCV's ORB for the same
///     keypoint, angle and level image.
/// A level with fewer corners than its share gives fewer features (as ORB-SLAM2): the total is
/// at most num_features.
///
/// Thread-safety: NOT thread-safe (it reuses internal buffers); use one extractor per thread
/// (e.g. one for the left and one for the right image). OpenCV may use its own worker threads
/// inside cv::resize / cv::GaussianBlur unless cv::setNumThreads(1) is set by the application.
class OrbExtractor {
 public:
  /// Throws std::invalid_argument with validate()'s message for an invalid config.
  explicit OrbExtractor(const OrbExtractorConfig& config);

  /// Extracts features of an 8-bit grey image. Throws std::invalid_argument (message naming
  /// the problem) for an empty image, a data size that does not match width * height, or a
  /// side smaller than OrbExtractorConfig::kMinImageSide.
  ExtractedFeatures extract(const GrayImage& image);
  /// The same for a CV_8UC1 matrix (any step). Throws std::invalid_argument for an empty
  /// matrix, another type, or a side smaller than kMinImageSide.
  ExtractedFeatures extract(const cv::Mat& image);

  const OrbExtractorConfig& config() const { return config_; }
  const ScalePyramid& scales() const { return scales_; }
  /// Features wanted at each level (sums to num_features).
  const std::vector<int>& featuresPerLevel() const { return features_per_level_; }

 private:
  OrbExtractorConfig config_;
  ScalePyramid scales_;
  std::vector<int> features_per_level_;
  OrbOrientation orientation_;
  RotatedBrief brief_;
  // Reused buffers.
  FastGridDetector fast_grid_;
  BriefBlur blur_;
  cv::Mat blurred_;
};

}  // namespace cblox
