#pragma once

#include <string>

#include "core/features/orb_extractor.h"
#include "core/features/stereo_depth.h"

namespace cblox {

/// Settings of stereo matching along the rows of a rectified pair (ORB-SLAM2's
/// Frame::ComputeStereoMatches). Pixel values are at the pyramid level named.
struct StereoMatcherConfig {
  /// A left keypoint's best right candidate is accepted when its Hamming distance is strictly
  /// below this, in [0, 257]. ORB-SLAM2: (TH_HIGH + TH_LOW) / 2 = (100 + 50) / 2 = 75.
  int max_descriptor_distance = 75;
  /// Right candidates may be detected this many octaves above or below the left keypoint's
  /// octave, >= 0. ORB-SLAM2: 1.
  int max_octave_difference = 1;
  /// A right keypoint of octave o is a candidate for left keypoints on rows within
  /// +- row_tolerance_factor * scale(o) level-0 pixels of its own row, > 0. ORB-SLAM2: 2.
  double row_tolerance_factor = 2.0;
  /// Closest depth searched, metres, > 0: the largest disparity is fx * baseline / min_depth_m
  /// (220 px for the simulator rig, fx 458 px and baseline 0.11 m). ORB-SLAM2 uses the
  /// baseline itself (a disparity of up to fx); 0.2 m is closer than a flying camera gets to
  /// anything, and a smaller search range has fewer false matches.
  double min_depth_m = 0.2;
  /// A match needs disparity strictly greater than this, level-0 pixels, >= 0.
  double min_disparity_px = 0.0;
  /// SAD refinement: half side of the square window, in [1, 64] (window (2w+1)^2 = 11x11).
  int sad_half_window = 5;
  /// How the SAD discounts a brightness offset between the two windows.
  enum class SadReference {
    /// Subtract each window's mean (default). On the simulator's exact images this cuts the
    /// median disparity error from 0.27 to 0.10 px and raises the matches within 2 % of the
    /// true depth from 75 % to 95 %: the centre pixel of a corner changes fast with a
    /// sub-pixel shift, so subtracting it distorts the cost curve.
    kWindowMean,
    /// Subtract each window's centre pixel (ORB-SLAM2).
    kCentrePixel,
  };
  SadReference sad_reference = SadReference::kWindowMean;
  /// Sub-pixel minimum of the SAD over the three offsets around the best one.
  enum class SubpixelFit {
    /// Parabola (ORB-SLAM2; default).
    kParabola,
    /// Two lines of equal and opposite slope ("equiangular", the shape of an L1 cost): median
    /// disparity error 0.07 px instead of 0.10 px on the simulator's exact images.
    kEquiangular,
  };
  SubpixelFit subpixel_fit = SubpixelFit::kParabola;
  /// SAD refinement: the window slides over +- this many pixels around the matched right
  /// keypoint, in [1, 64]; a minimum at either end is rejected (no bracketed minimum).
  int sad_search_half_range = 5;
  /// The parabola's sub-pixel shift must lie within +- this, pixels at the level, > 0.
  double max_subpixel_shift_px = 1.0;
  /// Matches whose best SAD exceeds this factor times the median best SAD of all matches of
  /// the pair are discarded, > 0. ORB-SLAM2: 1.5 * 1.4 = 2.1.
  double sad_outlier_factor = 2.1;

  /// Empty when valid, else a message naming the first bad field. Thread-safe.
  std::string validate() const;
};

/// Depth for the left keypoints of a rectified stereo pair by ORB-SLAM2's method
/// (Frame::ComputeStereoMatches):
///  1. right keypoints are indexed by row bands (row +- row_tolerance_factor * scale(octave));
///  2. for each left keypoint (u, v, octave o): among the right keypoints in the band of row
///     round(v) (and, exactly, |v - v_right| <= row_tolerance_factor * scale(octave_right)),
///     with octave in [o - 1, o + 1] and column in [u - d_max, u - min_disparity_px]
///     (d_max = fx * baseline_m / min_depth_m), the one of least Hamming distance, accepted if
///     the distance is below max_descriptor_distance;
///  3. SAD refinement on pyramid level o: an 11x11 window around the left keypoint, each
///     window's values taken relative to its mean (ORB-SLAM2: its centre pixel; see
///     sad_reference), slides over +- 5 px around the matched right column; the best offset
///     must not be at either end; a parabola (see subpixel_fit) through the SADs at the best
///     offset and its neighbours gives the sub-pixel shift (|shift| <= 1); windows that do not
///     fit in the level image reject the match;
///  4. disparity d = u - right_u (level-0 pixels) must be in (min_disparity_px, d_max):
///     right_u is stored and depth = fx * baseline_m / d;
///  5. matches whose SAD is more than sad_outlier_factor times the median SAD are discarded
///     (ORB-SLAM2 discards SAD >= the threshold, hence every match when the median is 0).
/// Several left keypoints may match the same right keypoint (as in ORB-SLAM2).
///
/// `left` and `right` come from OrbExtractor on the two rectified images (same size, same
/// pyramid settings); fx in pixels, baseline_m in metres (right camera at +baseline along x).
/// Throws std::invalid_argument (message naming the problem) for an invalid config,
/// non-positive or non-finite fx or baseline, features whose keypoint and descriptor counts
/// differ, or pyramids that differ in levels, scale factor or image size.
/// Thread-safe (pure).
StereoDepth matchStereo(const ExtractedFeatures& left, const ExtractedFeatures& right, double fx,
                        double baseline_m, const StereoMatcherConfig& config);

}  // namespace cblox
