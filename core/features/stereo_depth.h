#pragma once

#include <cstddef>
#include <vector>

namespace cblox {

/// Depth of each left keypoint from stereo matching or from a registered depth image, in
/// ORB-SLAM2's form (mvuRight, mvDepth). All vectors have one entry per left keypoint.
/// Plain value type.
struct StereoDepth {
  /// Column of the keypoint in the (real or virtual) right image, level-0 pixels, sub-pixel;
  /// < 0 when the keypoint has no depth.
  std::vector<float> right_u;
  /// Depth z along the left camera's axis, metres; < 0 when the keypoint has no depth.
  std::vector<float> depth;
  /// Index of the matched right keypoint (stereo matching only); -1 when unmatched or for
  /// depth from a depth image.
  std::vector<int> right_index;

  /// Keypoints with depth. Thread-safe.
  size_t numWithDepth() const {
    size_t n = 0;
    for (const float z : depth) n += z > 0.0f;
    return n;
  }
};

}  // namespace cblox
