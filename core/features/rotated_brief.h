#pragma once

#include <array>

#include <opencv2/core.hpp>

#include "core/features/orb_descriptor.h"
#include "core/features/orb_pattern.h"

namespace cblox {

/// Distance (pixels at the keypoint's level) from a keypoint to the farthest pixel that
/// rotated BRIEF reads: the pattern's points lie in [-13, 12]^2, so after any rotation and
/// rounding they lie within 13 * sqrt(2) < 19 pixels. Keypoints at least this far from the
/// level border need no bounds check.
inline constexpr int kRotatedBriefRadius = 19;

/// ORB's rotated BRIEF descriptor (256 bits, OpenCV's 31x31 pattern), computed exactly as
/// OpenCV's ORB (and ORB-SLAM2) compute it: for pair i with points a, b of the pattern and
/// the keypoint angle theta, a' = round(R(theta) a) (round half to even, float arithmetic as
/// OpenCV), bit i = I(center + a') < I(center + b'), on the Gaussian-blurred level image.
/// On CPUs with AVX2 the tests run eight pairs at a time (gathered pixels), with the same
/// float operations, so the bits are the same. Immutable after construction: thread-safe.
class RotatedBrief {
 public:
  RotatedBrief();

  /// Descriptor of the keypoint at pixel (round(x), round(y)) of `blurred_level` (CV_8UC1,
  /// the pyramid level blurred with BriefBlur) with orientation `angle_deg` (degrees). The
  /// caller guarantees that the keypoint is at least kRotatedBriefRadius pixels from every
  /// border (unchecked).
  OrbDescriptor compute(const cv::Mat& blurred_level, float x, float y, float angle_deg) const;

  /// The descriptor without the AVX2 path (SSE2 offsets, scalar tests): the reference the
  /// AVX2 path is tested against. Same contract as compute().
  OrbDescriptor computePortable(const cv::Mat& blurred_level, float x, float y,
                                float angle_deg) const;

 private:
  // compute() and computePortable(): the AVX2 path when `avx2`, else the portable one.
  OrbDescriptor describe(const cv::Mat& blurred_level, float x, float y, float angle_deg,
                         bool avx2) const;

  // Pattern coordinates as floats, by pair: a_x_[i], a_y_[i] is point a of pair i.
  alignas(32) std::array<float, kOrbPatternPairs> a_x_{};
  alignas(32) std::array<float, kOrbPatternPairs> a_y_{};
  alignas(32) std::array<float, kOrbPatternPairs> b_x_{};
  alignas(32) std::array<float, kOrbPatternPairs> b_y_{};
};

}  // namespace cblox
