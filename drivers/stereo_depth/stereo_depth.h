#pragma once

#include <memory>
#include <string>

#include "core/geometry/image.h"
#include "core/geometry/stereo_rig.h"

namespace cblox {

/// Which OpenCV matcher computes the disparity.
enum class StereoMatcherType {
  kSgbm,           ///< cv::StereoSGBM: semi-global matching, 5 paths (MODE_SGBM)
  kSgbm3Way,       ///< cv::StereoSGBM MODE_SGBM_3WAY: 3 paths, faster, slightly noisier
  kBlockMatching,  ///< cv::StereoBM: local block matching, cheapest, sparse on weak texture
};

/// "sgbm", "sgbm3way", "bm"; parseStereoMatcher reads them back (false for any other name).
/// Thread-safe (pure).
const char* stereoMatcherName(StereoMatcherType type);
bool parseStereoMatcher(const std::string& name, StereoMatcherType* type);

/// Dense depth from a rectified pair (config/capture.yaml `stereo_depth:`). Disparities are
/// searched at the working resolution (the rectified images shrunk by `downscale`), so
/// num_disparities there covers depths down to fx * baseline / (downscale * num_disparities)
/// of the full-resolution fx. Plain value type.
struct StereoDepthConfig {
  StereoMatcherType matcher = StereoMatcherType::kSgbm;
  /// 1 = full resolution, 2 = half (752x480 -> 376x240): about 4x cheaper.
  int downscale = 2;
  /// Disparity search range at the working resolution, pixels; a positive multiple of 16.
  int num_disparities = 64;
  /// Matching window, pixels; odd, 3..21 for SGBM, 5..255 for BM.
  int block_size = 5;
  /// Invalid unless the best cost beats the second best by this percentage (OpenCV's
  /// uniquenessRatio); 0 = off.
  int uniqueness_ratio = 10;
  /// Left-right check: invalid when the right-to-left disparity differs by more than this,
  /// pixels (OpenCV's disp12MaxDiff); < 0 = off.
  int left_right_max_diff = 1;
  /// Speckle filter: connected regions of fewer than speckle_window pixels whose disparity
  /// varies by at most speckle_range pixels are invalidated; speckle_window 0 = off.
  int speckle_window = 100;
  int speckle_range = 2;
  /// StereoBM only: invalid where the window's texture is below this; 0 = off.
  int texture_threshold = 10;
  /// Depths outside [min_depth_m, max_depth_m] are set to 0 (no measurement).
  double min_depth_m = 0.2;
  double max_depth_m = 10.0;

  /// "" when usable, else a message naming the first bad field. Thread-safe (pure).
  std::string validate() const;
};

/// What one compute() produced.
struct StereoDepthStats {
  int valid_pixels = 0;  ///< pixels with a depth in [min_depth_m, max_depth_m]
  int total_pixels = 0;
};

/// Metric depth for the rectified left camera from a rectified pair, with invalid pixels
/// masked (0): no disparity found, left-right check failed, not unique, speckle, outside the
/// depth range, and the left columns where the search range leaves the right image.
/// z = fx_w * baseline / d at the working resolution, d with OpenCV's 1/16 px sub-pixel step.
/// Not thread-safe (holds OpenCV's matcher and work buffers): one instance per thread.
class StereoDepthEstimator {
 public:
  /// Returns nullptr and a message when the config or the calibration is invalid (baseline
  /// must be > 0; the working image must be wider than num_disparities + block_size).
  static std::unique_ptr<StereoDepthEstimator> create(
      const RectifiedStereoCalibration& calibration, const StereoDepthConfig& config,
      std::string* error);
  ~StereoDepthEstimator();

  /// Intrinsics of the depth images (the rectified left camera at the working resolution:
  /// f / downscale, (c + 0.5) / downscale - 0.5).
  const PinholeIntrinsics& depthIntrinsics() const { return depth_intrinsics_; }
  const StereoDepthConfig& config() const { return config_; }

  /// Computes *depth (depthIntrinsics()' size). Throws std::invalid_argument when the images
  /// are not both of the calibration's size.
  StereoDepthStats compute(const GrayImage& left, const GrayImage& right, DepthImage* depth);

 private:
  struct Impl;
  StereoDepthEstimator() = default;

  RectifiedStereoCalibration calibration_;
  StereoDepthConfig config_;
  PinholeIntrinsics depth_intrinsics_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cblox
