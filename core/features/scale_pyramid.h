#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace cblox {

/// The scale factors of an image pyramid, as ORB-SLAM2 uses them: level i is the level-0 image
/// scaled by 1 / scale_factor^i. Per level: scale = scale_factor^i (level-i pixel size in
/// level-0 pixels), inv_scale = 1 / scale, sigma2 = scale^2 (variance of a keypoint position
/// measured at that level, in level-0 pixels^2, for one-pixel level noise), inv_sigma2.
/// Values are computed in float by repeated multiplication, exactly like ORB-SLAM2's
/// mvScaleFactor / mvLevelSigma2, so level sizes round the same way.
/// Immutable value type: all member functions are thread-safe.
class ScalePyramid {
 public:
  /// One level, scale factor 1.2.
  ScalePyramid() : ScalePyramid(1, 1.2) {}
  /// Throws std::invalid_argument (message from validate()) unless num_levels is in [1, 32]
  /// and scale_factor is finite and in (1, 4].
  ScalePyramid(int num_levels, double scale_factor);

  /// Empty when (num_levels, scale_factor) are usable, else a message naming the bad value.
  /// Thread-safe (pure).
  static std::string validate(int num_levels, double scale_factor);

  int numLevels() const { return static_cast<int>(scale_.size()); }
  double scaleFactor() const { return scale_factor_; }
  /// scale_factor^level; level in [0, numLevels()) (unchecked).
  float scale(int level) const { return scale_[static_cast<size_t>(level)]; }
  float invScale(int level) const { return inv_scale_[static_cast<size_t>(level)]; }
  float sigma2(int level) const { return sigma2_[static_cast<size_t>(level)]; }
  float invSigma2(int level) const { return inv_sigma2_[static_cast<size_t>(level)]; }

  /// Size of level `level` for a level-0 image of size `level0`:
  /// (cvRound(width * invScale), cvRound(height * invScale)), as ORB-SLAM2.
  cv::Size levelSize(cv::Size level0, int level) const;

  /// Builds the image pyramid of an 8-bit single-channel image: level 0 is a copy of `image`,
  /// level i > 0 is level i-1 resized to levelSize(image.size(), i) with cv::resize
  /// INTER_LINEAR (chained from the previous level, as ORB-SLAM2's ComputePyramid does; the
  /// size is that of level 0 scaled by 1/scale^i). Every level is a freshly allocated,
  /// continuous CV_8UC1 matrix. Levels whose size would be 0 are left empty. Throws
  /// std::invalid_argument for an empty image or a type other than CV_8UC1. Thread-safe.
  std::vector<cv::Mat> build(const cv::Mat& image) const;

 private:
  double scale_factor_ = 1.2;
  std::vector<float> scale_, inv_scale_, sigma2_, inv_sigma2_;
};

}  // namespace cblox
