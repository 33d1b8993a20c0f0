#pragma once

#include <array>
#include <cstdint>

#include <opencv2/core.hpp>

namespace cblox {

/// Radius (pixels at the keypoint's level) of the circular patch over which ORB measures a
/// keypoint's orientation: half of the 31-pixel patch, rounded down.
inline constexpr int kOrbHalfPatchSize = 15;

/// Orientation of keypoints by the intensity centroid (Rosin), as ORB and ORB-SLAM2 compute
/// it: the angle of (m10, m01) = sum over a circular patch of radius 15 around the keypoint of
/// (u, v) * I(u, v), using the same symmetric row extents ("umax" table) as OpenCV's ORB and
/// ORB-SLAM2, so angles equal theirs. Immutable after construction: thread-safe.
class OrbOrientation {
 public:
  OrbOrientation();

  /// Angle in degrees in [0, 360) (cv::fastAtan2(m01, m10)) of the keypoint at integer pixel
  /// (x, y) of `level` (CV_8UC1, the unblurred pyramid level). The caller guarantees that the
  /// patch lies inside the image: x and y at least 15 pixels from every border (unchecked).
  float angleDeg(const cv::Mat& level, int x, int y) const;

  /// umax[v]: half-width of the patch's row at vertical offset v (0 <= v <= 15).
  const std::array<int, kOrbHalfPatchSize + 1>& umax() const { return umax_; }

 private:
  std::array<int, kOrbHalfPatchSize + 1> umax_{};
  // Byte masks of each row's extent for the vectorised sums (see angleDeg).
  using Mask = std::array<uint8_t, 16>;
  alignas(16) std::array<Mask, kOrbHalfPatchSize + 1> mask_lo_{};
  alignas(16) std::array<Mask, kOrbHalfPatchSize + 1> mask_hi_{};
};

}  // namespace cblox
